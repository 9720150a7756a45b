# vi_ekf_slam — the two commands users need, and a few more for developers.
#   make demo   installs what is missing, builds, runs the main job, prints a table
#   make test   installs what is missing, builds, runs every test (non-zero exit on failure)
SHELL := /bin/bash
.SHELLFLAGS := -eo pipefail -c
# catkin, rostest and ROS Python live in Debian's /usr/bin python; the default python3 is a
# pyenv build without ROS modules.
export PATH := /usr/bin:/bin:/usr/sbin:/sbin:$(PATH)

ROOT     := $(CURDIR)
WS       ?= $(ROOT)/.catkin_ws
DATA_DIR ?= $(abspath $(ROOT)/../shared/data)
JOBS     ?= $(shell nproc)
# NATIVE=ON: compile for this machine's CPU (-march=native; see CMakeLists.txt). Off by default.
NATIVE   ?= OFF
# UNITY=OFF: compile file by file (quicker one-file rebuilds; a fresh build takes twice the CPU).
UNITY    ?= ON
export DATA_DIR
DEVEL    := $(WS)/devel
BIN      := $(DEVEL)/lib/vi_ekf_slam
# The scripts write their reports with the built vi_ekf_slam_report (tools/report.py), and every
# report records the commit it was measured on (docs/results.md says it per section).
export VI_EKF_SLAM_BIN := $(BIN)
export VI_EKF_SLAM_COMMIT := $(shell git -C $(ROOT) rev-parse --short HEAD 2>/dev/null)$(shell git -C $(ROOT) diff --quiet HEAD -- src include tools config 2>/dev/null || echo +changes)
CATKIN   := cd $(WS) && catkin_make -j$(JOBS) -DCMAKE_BUILD_TYPE=Release -DDATA_DIR=$(DATA_DIR) -DCMAKE_EXPORT_COMPILE_COMMANDS=ON -DVI_EKF_SLAM_NATIVE_ARCH=$(NATIVE) -DVI_EKF_SLAM_UNITY_BUILD=$(UNITY)

.PHONY: all deps workspace build test lint demo study suite initsuite bag screenshot bench soak realdata faults extrinsic params results rebuild-check clean help

BAG ?= results/bags/hallway.bag
RVIZ ?= 0

# make study [TRAJECTORY=file.txt] [IMU=imu0/data.csv] [RUNS=50] [SEED=1] [OUT=results/study] [CONFIGS=all|paper|a,b]
#   IMU: a recorded ASL IMU stream of the same recording as TRAJECTORY (real IMU, simulated camera)
#   IMU_NOISE: datasheet (the IMU's sensor.yaml) | euroc_mav (inflated for the MAV's vibration)
TRAJECTORY ?= builtin
IMU        ?=
IMU_NOISE  ?= datasheet
#   PRESET=openvins_sim: OpenVINS's simulator setup on TRAJECTORY (5 runs unless RUNS= is given)
PRESET     ?=
RUNS       ?= $(if $(PRESET),5,50)
SEED       ?= 1
CONFIGS    ?= all
#   STUDY_ARGS: more options of vi_ekf_slam_study, e.g. "--start-offset 10 --max-landmarks 150"
STUDY_ARGS ?=
OUT        ?= results/study/$(if $(PRESET),$(PRESET)_)$(if $(IMU),real_imu_$(IMU_NOISE)_$(notdir $(abspath $(dir $(TRAJECTORY))/../..)),$(basename $(notdir $(TRAJECTORY))))

all: build

help:
	@echo "make demo   - install, build, run the main job (results table + plots)"
	@echo "make test   - install, build, run all tests (non-zero exit on failure)"
	@echo "make build  - install missing packages and build in $(WS)"
	@echo "make study  - Monte-Carlo consistency study (TRAJECTORY=builtin|file.txt RUNS= SEED= OUT=)"
	@echo "make bag    - render the hallway walk into $(BAG)"
	@echo "make demo RVIZ=1 - the demo with rviz"
	@echo "make suite  - the study over every trajectory in windows + generated walks, one table with worst cases -> results/suite"
	@echo "make initsuite - starts mid-walk as the node starts, against starts from the truth and from the prior (docs/initialization.md) -> results/init_suite"
	@echo "make realdata - the real hand-held recording (DATA_DIR/dmvio_handheld) -> results/realdata"
	@echo "make faults - faulty copies of the real recording and the rendered walk, one fault class at a time -> results/faults"
	@echo "make extrinsic - the online camera-IMU extrinsic from a calibration 3 deg / 3 cm off, real recording and study -> results/extrinsic"
	@echo "make bench  - benchmarks (core vs map size, tracker, pipeline) -> results/bench/summary.json"
	@echo "make soak   - 30 min endurance walk per mechanization (SOAK_MINUTES=, SOAK_MAP=keep) -> results/soak_forget, results/soak_keep"
	@echo "make results - docs/results.md (and the README's quote) from the results of demo, realdata, suite, bench"
	@echo "make lint   - catkin_lint, clang-format, pyflakes on the Python, clang-tidy on the core (part of make test)"
	@echo "make clean  - remove the build workspace"

deps:
	@bash tools/install_deps.sh

# The catkin workspace lives outside the sources (git-ignored). Its src/vi_ekf_slam is a real
# directory whose entries link to this repository's top-level items, so tools that follow
# symlinks (rosrun, roslib) never loop back into the workspace.
PKG_LINK := $(WS)/src/vi_ekf_slam
# catkin caches PYTHONPATH at configure time and leaves out folders that do not exist yet, so the
# devel Python folder (generated messages, used by the Python rostests) is created first.
workspace:
	@mkdir -p $(WS)/src $(DEVEL)/lib/python3/dist-packages
	@if [ -L $(PKG_LINK) ]; then rm $(PKG_LINK); fi
	@mkdir -p $(PKG_LINK)
	@find $(PKG_LINK) -maxdepth 1 -xtype l -delete
	@for f in $$(ls -A $(ROOT)); do \
	  case "$$f" in .catkin_ws|.git|results) ;; *) ln -sfn $(ROOT)/$$f $(PKG_LINK)/$$f ;; esac; \
	done

build: deps workspace
	$(CATKIN)

# Hygiene (configs: .clang-format, .clang-tidy): catkin_lint without errors or warnings, every
# C++ file formatted, the Python without pyflakes findings, clang-tidy clean on the ROS-free core
# (compile_commands.json from the build).
CXX_SOURCES = $(shell find src include test tools bench -name '*.cc' -o -name '*.h')
lint: build
	catkin_lint --strict $(PKG_LINK)
	@# package.xml declares exactly what CMake, the includes, the Python imports and the launch files use.
	/usr/bin/python3 test/install/check_package_xml.py $(ROOT)
	/usr/bin/python3 test/install/check_rviz_views.py $(ROOT)
	@# roslaunch ignores unknown arguments: the documented commands name only declared ones.
	/usr/bin/python3 test/install/check_readme_commands.py $(ROOT)
	@clang-format --dry-run --Werror $(CXX_SOURCES) && echo "clang-format: clean"
	@pyflakes3 $$(git ls-files '*.py' 2>/dev/null || find tools bench test -name '*.py') && echo "pyflakes: clean"
	@# One clang-tidy per translation unit of the core as it is compiled (a batch of its files in a
	@# unity build: its .cc files are then included ones, hence the header filter and the
	@# suspicious-include check off), as many at once as there are cores.
	/usr/bin/python3 -c "import json, sys; print('\n'.join(e['file'] for e in json.load(open(sys.argv[1])) \
	  if '/vi_ekf_slam_core.dir/' in e['command']))" $(WS)/build/compile_commands.json | \
	  xargs -P $$(nproc) -n 1 clang-tidy -p $(WS)/build --quiet --header-filter='(src|include/vi_ekf_slam)/core/' \
	  --checks=-bugprone-suspicious-include 2>&1 | { grep -v "warnings generated" || true; }
	@echo "lint: clean"

# A second build with nothing changed must compile nothing (a generator re-running at every build
# recompiles what includes its output).
rebuild-check: build
	@$(CATKIN) > $(WS)/rebuild.log 2>&1 || { tail -n 30 $(WS)/rebuild.log; exit 1; }
	@if grep -E "Building CXX|Generating" $(WS)/rebuild.log; then \
	  echo "rebuild-check: a second build with nothing changed did the work above"; exit 1; fi
	@echo "rebuild-check: a second build compiles nothing"

test: build lint rebuild-check
	$(CATKIN) tests
	@# The package installed into a prefix runs (run_bag, replay.launch) without the source tree.
	bash test/install/check_installed.sh $(WS)
	@rm -rf $(WS)/build/test_results
	@# Two tests at a time: the rostests wait for their stream's end (no wall-clock window) and
	@# each starts its own master on a free port.
	$(CATKIN) run_tests -j2 | tail -n 200
	@echo "================================ test summary ================================"
	cd $(WS) && catkin_test_results build/test_results

# The files generated from the parameter table (src/ros/param_table.cc): the documented YAML, the
# dynamic_reconfigure definition and the reference. A test fails while a committed copy is stale.
params: build
	$(BIN)/vi_ekf_slam_params --yaml > config/vi_ekf_slam.yaml
	$(BIN)/vi_ekf_slam_params --cfg > cfg/EkfSlamReconfigure.cfg
	$(BIN)/vi_ekf_slam_params --markdown > docs/parameters.md

# docs/results.md, every current number, from the result files of make demo, realdata, suite and
# bench; the README quotes its first section (a test fails while the quote differs).
results:
	python3 tools/results_page.py --results results --out docs/results.md --readme README.md

# The rendered hallway walk (2 s standing + 35 s walk), cached until the renderer changes.
bag: build $(BAG)
$(BAG): $(BIN)/vi_ekf_slam_make_bag
	@mkdir -p $(dir $(BAG))
	$(BIN)/vi_ekf_slam_make_bag --out $(BAG) --duration 35 --standing 2

# rviz under Xvfb during a replay; results/demo/rviz.png (and docs/img/rviz.png for the README).
screenshot: build $(BAG)
	source $(DEVEL)/setup.bash && tools/screenshot.sh $(BAG) results/demo/rviz.png 25
	cp results/demo/rviz.png docs/img/rviz.png

# The main job: the bag through the nodelet with roslaunch, once per mechanization.
demo: build $(BAG)
	source $(DEVEL)/setup.bash && python3 tools/demo.py --bag $(BAG) --out results/demo --docs docs/img $(if $(filter 1,$(RVIZ)),--rviz)

# The plots of the built-in walk and of the TUM corridor are copied to docs/img for the README,
# only from the study itself (not from a preset, a recorded IMU or extra options).
DOCS_STUDY = $(and $(filter builtin %tum_corridor1_512_16_okvis.txt,$(TRAJECTORY)),$(if $(PRESET)$(IMU)$(STUDY_ARGS),,yes))
study: build
	$(BIN)/vi_ekf_slam_study --trajectory $(TRAJECTORY) --runs $(RUNS) --seed $(SEED) --configs $(CONFIGS) --out $(OUT) $(if $(IMU),--imu $(IMU) --imu-noise $(IMU_NOISE)) $(if $(PRESET),--preset $(PRESET)) $(STUDY_ARGS)
	python3 tools/plot_study.py $(OUT) $(if $(DOCS_STUDY),--docs docs/img --prefix study_$(basename $(notdir $(TRAJECTORY))))

# Benchmarks (numbers, not pass/fail), pinned to one core: core operations against the map size
# with fitted growth exponents, the tracker on rendered and real frames, the offline pipeline's
# real-time factor and the live replay's latency. Table in bench/README.md.
bench: build $(BAG) $(if $(wildcard $(DATA_DIR)/dmvio_handheld/mav0),results/bags/dmvio_handheld.bag)
	@mkdir -p results/bench
	taskset -c 0 $(BIN)/vi_ekf_slam_bench --benchmark_repetitions=3 --benchmark_report_aggregates_only=true \
	  --benchmark_min_time=0.2 --benchmark_out=results/bench/google_benchmark.json --benchmark_out_format=json
	source $(DEVEL)/setup.bash && python3 bench/pipeline.py --bag $(BAG) --config config/sim_hallway.yaml --out results/bench \
	  $(if $(wildcard $(REAL)/mav0),--real-bag $(REAL_BAG))
	python3 bench/summarize.py results/bench/google_benchmark.json results/bench/pipeline.json results/bench

# The suite (docs/evaluation.md): the study with the same seeds over the built-in walk, every
# trajectory in DATA_DIR/trajectories (120 s windows) and the simulator's generated walks; one
# table per case and configuration plus the worst case of each configuration; SEED=1,2,3: each seed
# in SUITE_OUT/seed_N and the worst over all seeds in SUITE_OUT/suite_seeds.md. Then the map's
# walks (there and back, laps; unique and tiled texture), the map kept and forgotten:
# SUITE_OUT/map/suite_map.md (SUITE_MAP=no skips them, SUITE_MAP=only runs only them).
#   make suite [SUITE_RUNS=8] [SEED=1] [SUITE_CONFIGS=a,b] [SUITE_OUT=results/suite] [STUDY_ARGS=...]
#              [SUITE_WALKS=kind,..|all]  (vi_ekf_slam_make_walks kinds; all: with the probe walks)
#              [SUITE_MAP=no|only]
SUITE_RUNS    ?= 8
SUITE_OUT     ?= results/suite
SUITE_CONFIGS ?=
SUITE_WALKS   ?=
SUITE_MAP     ?=
suite: build
	python3 tools/suite.py --study $(BIN)/vi_ekf_slam_study --data $(DATA_DIR) --out $(SUITE_OUT) --runs $(SUITE_RUNS) \
	  --seed $(SEED) --threads $(JOBS) $(if $(SUITE_CONFIGS),--configs $(SUITE_CONFIGS)) \
	  $(if $(SUITE_WALKS),--walks $(SUITE_WALKS)) $(if $(filter no,$(SUITE_MAP)),--no-map) \
	  $(if $(filter only,$(SUITE_MAP)),--map-only) $(if $(STUDY_ARGS),-- $(STUDY_ARGS))

# Starting mid-walk (docs/initialization.md): on the built-in walk, every trajectory in
# DATA_DIR/trajectories and the simulator's generated walks, the study from 5 random start times
# (20 runs) with the node's default configuration, started as the node starts (at rest or moving),
# from the truth and from the prior; one table.
#   make initsuite [SEED=1] [INIT_OUT=results/init_suite]
INIT_OUT ?= results/init_suite
initsuite: build
	python3 tools/init_suite.py --study $(BIN)/vi_ekf_slam_study --data $(DATA_DIR) --out $(INIT_OUT) --seed $(SEED) \
	  --threads $(JOBS)

# The real hand-held recording (../shared/data/dmvio_handheld, docs/realdata.md): its ASL folder as
# a rig bag (cached), then the node's processor offline for the three mechanizations with the
# default configuration, and the default with the rig file; each against the SfM reference (camera
# poses, camera clock), OpenVINS (IMU poses, IMU clock) and the SfM reference from 15 s on (the data
# set's README trusts its first 15 s less). Tables, health and reference plots.
REAL      := $(DATA_DIR)/dmvio_handheld
REAL_BAG  := results/bags/dmvio_handheld.bag
REAL_REFS := --reference $(REAL)/reference/sfm_camera_poses.txt --reference-frame camera --reference-clock camera --reference-from-s 0 \
             --reference $(REAL)/reference/openvins_imu_poses.txt --reference-frame body --reference-clock imu --reference-from-s 0 \
             --reference $(REAL)/reference/sfm_camera_poses.txt --reference-frame camera --reference-clock camera --reference-from-s 15 \
             --reference $(REAL)/reference/sfm_camera_poses.txt --reference-frame camera --reference-clock camera --reference-from-s 20
$(REAL_BAG): $(BIN)/vi_ekf_slam_asl_to_bag
	@mkdir -p $(dir $@)
	$(BIN)/vi_ekf_slam_asl_to_bag --asl $(REAL)/mav0 --out $@
realdata: build $(REAL_BAG)
	source $(DEVEL)/setup.bash && $(BIN)/vi_ekf_slam_run_bag --bag $(REAL_BAG) --out results/realdata/defaults --mechanization all $(REAL_REFS)
	source $(DEVEL)/setup.bash && $(BIN)/vi_ekf_slam_run_bag --bag $(REAL_BAG) --out results/realdata/rig --rig config/rigs/dmvio_handheld.yaml $(REAL_REFS)
	@# The map kept (keep_map), with the defaults and the rig file, and across a reset forced at 30 s.
	source $(DEVEL)/setup.bash && $(BIN)/vi_ekf_slam_run_bag --bag $(REAL_BAG) --out results/realdata/defaults_keep_map --param keep_map=true $(REAL_REFS)
	source $(DEVEL)/setup.bash && $(BIN)/vi_ekf_slam_run_bag --bag $(REAL_BAG) --out results/realdata/rig_keep_map --rig config/rigs/dmvio_handheld.yaml --param keep_map=true $(REAL_REFS)
	source $(DEVEL)/setup.bash && $(BIN)/vi_ekf_slam_run_bag --bag $(REAL_BAG) --out results/realdata/defaults_keep_map_reset_30s --param keep_map=true --reset-at 30 $(REAL_REFS)

# Faults (docs/evaluation.md): faulty copies of the real hand-held recording and of the rendered
# walk, one class at a time (clipped IMU samples, sensor gaps, a covered lens, NaN IMU samples, dim
# images, a lossy link, darkness), each through the node's processor; one table (results/faults/faults.md).
faults: build $(REAL_BAG) $(BAG)
	source $(DEVEL)/setup.bash && python3 tools/fault_matrix.py --bin $(BIN) --out results/faults \
	  --bag real=$(REAL_BAG):$(REAL)/reference/sfm_camera_poses.txt --bag rendered=$(BAG) --study \
	  --sizes covered_lens=4,6,10

# The online camera-IMU extrinsic (docs/evaluation.md): the real recording from its rig file's
# extrinsic and from four copies 3 deg / 3 cm off, fixed and estimated; the study per start.
extrinsic: build $(REAL_BAG)
	source $(DEVEL)/setup.bash && python3 tools/extrinsic_perturbation.py --bin $(BIN) --out results/extrinsic \
	  --bag $(REAL_BAG) --rig config/rigs/dmvio_handheld.yaml --reference $(REAL)/reference/sfm_camera_poses.txt --study

# Endurance: a 30-minute walk (laps) per mechanization through the core; error, map size and
# resident memory over time (a 4-minute version runs in make test).
SOAK_MINUTES ?= 30
SOAK_MAP ?= forget
soak: build
	$(BIN)/vi_ekf_slam_soak --minutes $(SOAK_MINUTES) --map $(SOAK_MAP) --out results/soak_$(SOAK_MAP)
	python3 tools/plot_soak.py results/soak_$(SOAK_MAP) $(if $(filter forget,$(SOAK_MAP)),--docs docs/img)

clean:
	rm -rf $(WS)
