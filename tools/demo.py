#!/usr/bin/python3
"""The main job (`make demo`): replays the rendered hallway bag with
`roslaunch vi_ekf_slam replay.launch` through the nodelet once per mechanization, set with
dynamic_reconfigure, records the outputs, scores them against the bag's ground truth and writes
a table and plots to results/demo/.

usage: demo.py --bag BAG [--out DIR] [--config YAML] [--rviz] [--rate R] [--start S]
               [--mechanizations a,b]

--start S plays the bag from S seconds in (replay.launch start:=S): the node starts mid-walk.
"""
import argparse
import os
import socket
import subprocess
import sys
import time

MECHANIZATIONS = ["world_centric", "sensor_centric", "sensor_centric_composition"]


def free_port():
    s = socket.socket()
    s.bind(("", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def replay(bag, mech, out, config, rviz, rate, log, start=0.0):
    """One live replay; returns the recorded bag."""
    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI="http://localhost:%d" % port)
    rec = os.path.abspath(os.path.join(out, mech))  # nodes run in ~/.ros
    if os.path.exists(rec + ".bag"):
        os.remove(rec + ".bag")
    launch = subprocess.Popen(
        ["roslaunch", "-p", str(port), "vi_ekf_slam", "replay.launch", "bag:=" + bag, "config:=" + config,
         "delay:=8", "rate:=%g" % rate, "start:=%g" % start, "record:=" + rec, "rviz:=%s" % ("true" if rviz else "false"),
         "rviz_config:=hallway_demo.rviz", "follow:=false"],
        env=env, stdout=log, stderr=subprocess.STDOUT)
    # Switch the running filter to this mechanization before the bag starts (delay above).
    deadline = time.time() + 40
    switched = False
    while time.time() < deadline and launch.poll() is None:
        # dynparam waits for a master for ever: a launch that failed (its master gone) must not hang here.
        try:
            r = subprocess.run(["rosrun", "dynamic_reconfigure", "dynparam", "set", "/vi_ekf_slam/filter",
                                "mechanization", mech], env=env, stdout=log, stderr=subprocess.STDOUT, timeout=10)
            # Read it back: a results table labelled with a mechanization that did not run is worse than none.
            got = subprocess.run(["rosrun", "dynamic_reconfigure", "dynparam", "get", "/vi_ekf_slam/filter"], env=env,
                                 capture_output=True, text=True, timeout=10).stdout
        except subprocess.TimeoutExpired:
            continue
        if r.returncode == 0 and "'mechanization': '%s'" % mech in got:
            switched = True
            break
        time.sleep(0.5)
    if not switched:
        launch.terminate()
        raise RuntimeError("could not set the mechanization through dynamic_reconfigure (see %s)" % log.name)
    launch.wait()
    if not os.path.exists(rec + ".bag"):
        raise RuntimeError("the replay recorded nothing (see %s)" % log.name)
    return rec + ".bag"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bag", required=True)
    ap.add_argument("--out", default="results/demo")
    ap.add_argument("--config", default=None)
    ap.add_argument("--rviz", action="store_true")
    ap.add_argument("--rate", type=float, default=1.0)
    ap.add_argument("--docs", default="")
    ap.add_argument("--start", type=float, default=0.0, help="seconds into the bag to start at")
    ap.add_argument("--mechanizations", default=",".join(MECHANIZATIONS))
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    config = a.config or subprocess.run(["rospack", "find", "vi_ekf_slam"], capture_output=True,
                                        text=True).stdout.strip() + "/config/sim_hallway.yaml"
    recorded = []
    with open(os.path.join(a.out, "roslaunch.log"), "w") as log:
        for mech in a.mechanizations.split(","):
            t0 = time.time()
            print("replaying %s through the nodelet (mechanization %s) ..." % (os.path.basename(a.bag), mech), flush=True)
            recorded.append("%s=%s" % (mech, replay(os.path.abspath(a.bag), mech, a.out, config, a.rviz, a.rate, log,
                                                    a.start)))
            print("  done in %.0f s" % (time.time() - t0), flush=True)
    r = subprocess.run(["rosrun", "vi_ekf_slam", "vi_ekf_slam_run_bag", "--bag", a.bag, "--no-plots", "--out", a.out]
                       + [x for r in recorded for x in ("--recorded", r)], capture_output=True, text=True)
    if r.returncode != 0:
        print(r.stdout, r.stderr)
        return 1
    print()
    print("Hallway walk (rendered, 37 s%s) through the nodelet, one live replay per mechanization:" %
          (", played from %g s" % a.start if a.start > 0 else ""))
    with open(os.path.join(a.out, "summary.md")) as f:
        print(f.read())
    cmd = ["python3", os.path.join(os.path.dirname(os.path.abspath(__file__)), "plot_run.py"), a.out]
    if a.docs:
        cmd += ["--docs", a.docs, "--prefix", "demo"]
    subprocess.run(cmd, check=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
