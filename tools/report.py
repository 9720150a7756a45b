"""The scripts' side of the one report schema (eval/report.h):

  {"schema": "vi_ekf_slam.report/1", "tool": ..., "title": ..., "config": {settings},
   "runs": {name: {metric: value}}, "tables": {name: {row: {column: value}}}}

report() builds the object; write_report() hands it to vi_ekf_slam_report, the C++ tools' own
writer of the JSON and the Markdown (a column given as a metric key takes the one header and
precision of eval/report_columns.h); load() reads any tool's report.
"""
import json
import math
import os
import shutil
import subprocess

SCHEMA = "vi_ekf_slam.report/1"
# The study's rows in the scripts' tables (fault_matrix.py, extrinsic_perturbation.py): metric keys.
STUDY_COLUMNS = ["ate_position_m", "nees_pose", "band_lo", "band_hi", "inside_band", "consistent_fraction"]


def _clean(v):
    """Non-finite numbers as None (JSON null), recursively."""
    if isinstance(v, float) and not math.isfinite(v):
        return None
    if isinstance(v, dict):
        return {k: _clean(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_clean(x) for x in v]
    return v


def report(tool, title, config, runs, tables=None):
    """The JSON object of a report (tables: {name: rows})."""
    r = {"schema": SCHEMA, "tool": tool, "title": title, "config": config, "runs": runs}
    if tables:
        r["tables"] = tables
    return _clean(r)


def _writer():
    """vi_ekf_slam_report: in VI_EKF_SLAM_BIN, beside this module (installed), on PATH, or by rosrun."""
    for d in (os.environ.get("VI_EKF_SLAM_BIN"), os.path.dirname(os.path.abspath(__file__))):
        if d and os.access(os.path.join(d, "vi_ekf_slam_report"), os.X_OK):
            return [os.path.join(d, "vi_ekf_slam_report")]
    found = shutil.which("vi_ekf_slam_report")
    return [found] if found else ["rosrun", "vi_ekf_slam", "vi_ekf_slam_report"]


def write_report(out_dir, stem, r, columns=None, table_columns=None, headings=None, notes=()):
    """OUT_DIR/STEM.json and OUT_DIR/STEM.md; returns the Markdown. columns (of the runs' table)
    and table_columns {table: columns}: metric keys, or (key, header, digits) for a script's own
    column; None: every key of the rows."""
    spec = {"out": out_dir, "stem": stem, "report": r, "columns": columns, "table_columns": table_columns or {},
            "headings": headings or {}, "notes": list(notes)}
    p = subprocess.run(_writer(), input=json.dumps(_clean(spec)), capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError("vi_ekf_slam_report: " + p.stderr.strip())
    return p.stdout


def load(path):
    """A report written by any tool; raises ValueError for a file of another schema."""
    with open(path) as f:
        r = json.load(f)
    if not isinstance(r, dict) or r.get("schema") != SCHEMA:
        raise ValueError("%s: not a %s report" % (path, SCHEMA))
    return r
