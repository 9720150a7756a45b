"""The command-line options every script that drives the study binary shares (suite.py, init_suite.py)."""
import os


def add_study_options(ap, out, runs):
    """--study, --data, --out and --runs, with this script's output folder and runs per case."""
    ap.add_argument("--study", required=True, help="the vi_ekf_slam_study binary")
    ap.add_argument("--make-walks", help="the vi_ekf_slam_make_walks binary (default: beside --study)")
    ap.add_argument("--data", default=os.environ.get("DATA_DIR", "../shared/data"))
    ap.add_argument("--out", default=out)
    ap.add_argument("--runs", type=int, default=runs)


def resolve_tools(a):
    """--make-walks defaults to the binary beside --study."""
    if not a.make_walks:
        a.make_walks = os.path.join(os.path.dirname(os.path.abspath(a.study)), "vi_ekf_slam_make_walks")
    return a
