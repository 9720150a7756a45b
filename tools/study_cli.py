"""The command-line options every script that drives the study binary shares (suite.py, init_suite.py)."""
import os


def add_study_options(ap, out, runs):
    """--study, --data, --out and --runs, with this script's output folder and runs per case."""
    ap.add_argument("--study", required=True, help="the vi_ekf_slam_study binary")
    ap.add_argument("--data", default=os.environ.get("DATA_DIR", "../shared/data"))
    ap.add_argument("--out", default=out)
    ap.add_argument("--runs", type=int, default=runs)
