"""The one report schema of the tools, from Python (eval/report.h writes the same from C++):

  {"schema": "vi_ekf_slam.report/1", "tool": ..., "title": ..., "config": {settings},
   "runs": {name: {metric: value}}, "tables": {name: {row: {column: value}}}}

("tables" only with more tables than the runs; non-finite numbers as null) and the same as
Markdown: the title, the settings, one table per table, notes.
"""
import json
import math
import os

SCHEMA = "vi_ekf_slam.report/1"


def _clean(v):
    """Non-finite numbers as None (JSON null), recursively."""
    if isinstance(v, float) and not math.isfinite(v):
        return None
    if isinstance(v, dict):
        return {k: _clean(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_clean(x) for x in v]
    return v


def _cell(v, digits):
    if v is None:
        return "-"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return "%.*f" % (digits, v) if math.isfinite(v) else "-"
    return str(v)


def _table(rows, columns, heading=None):
    """Markdown lines of a table: rows {name: {key: value}}, columns [(key, header, digits)] (None:
    every key of the rows, 3 decimals)."""
    if columns is None:
        keys = []
        for row in rows.values():
            keys += [k for k in row if k not in keys]
        columns = [(k, k, 3) for k in keys]
    out = ["## " + heading, ""] if heading else []
    out.append("| |" + "".join(" %s |" % c[1] for c in columns))
    out.append("|---|" + "---|" * len(columns))
    for name, row in rows.items():
        out.append("| %s |" % name + "".join(" %s |" % _cell(row.get(c[0]), c[2]) for c in columns))
    return out + [""]


def report(tool, title, config, runs, tables=None):
    """The JSON object of a report (tables: {name: rows})."""
    r = {"schema": SCHEMA, "tool": tool, "title": title, "config": config, "runs": runs}
    if tables:
        r["tables"] = tables
    return _clean(r)


def markdown(r, columns=None, table_columns=None, headings=None, notes=()):
    """The Markdown of a report object: columns of the runs' table, and per extra table its
    columns and heading."""
    settings = ", ".join("%s %s" % (k, v) for k, v in r["config"].items())
    lines = ["# " + r["title"], ""] + (["Settings: %s." % settings, ""] if settings else [])
    lines += _table(r["runs"], columns)
    for name, rows in r.get("tables", {}).items():
        lines += _table(rows, (table_columns or {}).get(name), (headings or {}).get(name))
    for n in notes:
        lines += [n, ""]
    return "\n".join(lines)


def write_report(out_dir, stem, r, **md):
    """OUT_DIR/STEM.json and OUT_DIR/STEM.md; returns the Markdown."""
    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, stem + ".json"), "w") as f:
        json.dump(r, f, indent=2)
        f.write("\n")
    text = markdown(r, **md)
    with open(os.path.join(out_dir, stem + ".md"), "w") as f:
        f.write(text)
    return text


def load(path):
    """A report written by any tool; raises ValueError for a file of another schema."""
    with open(path) as f:
        r = json.load(f)
    if not isinstance(r, dict) or r.get("schema") != SCHEMA:
        raise ValueError("%s: not a %s report" % (path, SCHEMA))
    return r
