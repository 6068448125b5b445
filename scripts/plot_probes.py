#!/usr/bin/python3
"""Plot the probe time series of an mpsfsi run (probes.csv) to a PNG, optionally against reference data.

One figure with a subplot per probe column (all columns except `time`, or those given by --columns),
stacked and sharing the x axis. A reference file (CSV or TSV, `#` comment lines, first other line is
the header) can be drawn into one of the subplots (--ref-target, default the first plotted column).

Values can be transformed before plotting with simple expressions:
  --x-expr / --y-expr          applied to the run's data;
  --ref-x-expr / --ref-y-expr  applied to the reference data.
An expression may use the file's column names (those that are Python identifiers), `x` (the x column,
`time` by default), `y` (the column being plotted), constants given with --const NAME=VALUE, the
numbers pi and e, the operators + - * / ** % and parentheses, and the functions sqrt exp log log10 abs
sin cos tan arcsin arccos arctan sinh cosh tanh minimum maximum. Nothing else is evaluated.
--scale-x / --scale-y multiply the run's x / y after the expression.

Examples
  # all probes of a run, against time
  scripts/plot_probes.py out/dam_break/probes.csv --output front.png
  # dam-break surge front, nondimensional, against Martin & Moyce (1952): T = t sqrt(2g/L), Z = x/L
  scripts/plot_probes.py out/dam_break/probes.csv --columns front \\
      --x-expr 'time*sqrt(2*g/L)' --y-expr 'front/L' --const L=0.146 g=9.81 \\
      --reference cases/dam_break/martin_moyce_1952_surge_front.csv --ref-columns T,Z \\
      --xlabel 'T = t sqrt(2g/L)' --ylabel 'Z = x/L' --output surge_front.png
  # displacement against a TSV with two reference curves (x column, then the y columns)
  scripts/plot_probes.py out/obstacle/probes.csv --columns tip_dx \\
      --reference walhorn.tsv --ref-columns 'x,Meduri et al.,Ryzhakov et al.' --output tip.png

Exit codes: 0 success, 2 bad input (missing file, unknown column, bad expression), with a message.
Needs Debian's python3-matplotlib (run with /usr/bin/python3 if another python3 comes first in PATH).
"""

import argparse
import ast
import math
import operator
import os
import re
import sys


def fail(msg):
    print(f"plot_probes.py: error: {msg}", file=sys.stderr)
    sys.exit(2)


try:
    import numpy as np
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError as exc:  # pragma: no cover - depends on the system
    fail(f"{exc}; install Debian's python3-matplotlib and run with /usr/bin/python3")


# ---------------------------------------------------------------------------------------------------
# Reading CSV / TSV tables with '#' comments.

def read_table(path):
    """Return (names, columns dict name -> numpy array) of a CSV/TSV/whitespace table with a header."""
    if not os.path.isfile(path):
        fail(f"{path}: no such file")
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            lines = [ln.rstrip("\r\n") for ln in f]
    except OSError as exc:
        fail(f"{path}: {exc.strerror}")
    rows = [(n + 1, ln) for n, ln in enumerate(lines) if ln.strip() and not ln.lstrip().startswith("#")]
    if not rows:
        fail(f"{path}: no header line (the file is empty or only comments)")
    header_no, header = rows[0]
    if "\t" in header:
        split = lambda s: [c.strip() for c in s.split("\t")]
    elif "," in header:
        split = lambda s: [c.strip() for c in s.split(",")]
    elif ";" in header:
        split = lambda s: [c.strip() for c in s.split(";")]
    else:
        split = lambda s: s.split()
    names = split(header)
    if all(_is_number(n) for n in names):  # no header: name the columns c1, c2, ...
        names = [f"c{i + 1}" for i in range(len(names))]
        data_rows = rows
    else:
        data_rows = rows[1:]
    if len(set(names)) != len(names):
        fail(f"{path}:{header_no}: repeated column names in header {names}")
    values = []
    for n, ln in data_rows:
        cells = split(ln)
        if len(cells) != len(names):
            fail(f"{path}:{n}: {len(cells)} values, expected {len(names)} (columns {', '.join(names)})")
        try:
            values.append([float(c) if c else math.nan for c in cells])
        except ValueError:
            fail(f"{path}:{n}: not a number in line '{ln.strip()}'")
    arr = np.array(values, dtype=float).reshape(len(values), len(names))
    return names, {name: arr[:, i] for i, name in enumerate(names)}


def _is_number(s):
    try:
        float(s)
        return True
    except ValueError:
        return False


def column(table, name, path):
    names, cols = table
    if name not in cols:
        fail(f"{path}: unknown column '{name}'; the columns are: {', '.join(names)}")
    return cols[name]


# ---------------------------------------------------------------------------------------------------
# Safe evaluation of simple arithmetic expressions over numpy arrays.

_BINOPS = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv,
           ast.Pow: operator.pow, ast.Mod: operator.mod}
_UNOPS = {ast.UAdd: operator.pos, ast.USub: operator.neg}
_FUNCS = {name: getattr(np, name) for name in ("sqrt", "exp", "log", "log10", "abs", "sin", "cos", "tan", "arcsin",
                                               "arccos", "arctan", "sinh", "cosh", "tanh", "minimum", "maximum")}


def evaluate(expr, names, what):
    """Evaluate `expr` with the variables in `names`; only arithmetic and the functions in _FUNCS."""
    try:
        tree = ast.parse(expr, mode="eval")
    except SyntaxError as exc:
        fail(f"{what} '{expr}': syntax error: {exc.msg}")

    def ev(node):
        if isinstance(node, ast.Expression):
            return ev(node.body)
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)):
            return node.value
        if isinstance(node, ast.Name):
            if node.id in names:
                return names[node.id]
            fail(f"{what} '{expr}': unknown name '{node.id}'; known: {', '.join(sorted(names))}")
        if isinstance(node, ast.BinOp) and type(node.op) in _BINOPS:
            return _BINOPS[type(node.op)](ev(node.left), ev(node.right))
        if isinstance(node, ast.UnaryOp) and type(node.op) in _UNOPS:
            return _UNOPS[type(node.op)](ev(node.operand))
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in _FUNCS
                and not node.keywords):
            return _FUNCS[node.func.id](*[ev(a) for a in node.args])
        fail(f"{what} '{expr}': not allowed: '{ast.unparse(node)}' (only numbers, column names, constants, "
             f"+ - * / ** %, and the functions {', '.join(_FUNCS)})")

    with np.errstate(all="ignore"):
        return np.asarray(ev(tree), dtype=float)


def variables(table, consts):
    names, cols = table
    env = {"pi": math.pi, "e": math.e}
    env.update({n: c for n, c in cols.items() if n.isidentifier()})
    env.update(consts)
    return env


# ---------------------------------------------------------------------------------------------------

def parse_args(argv):
    p = argparse.ArgumentParser(
        description="Plot an mpsfsi probes.csv to PNG, optionally against a reference file.",
        epilog="See the module docstring (head of this file) for the expression syntax and examples.",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("probes", help="probe file of a run (probes.csv: header time,<columns>)")
    p.add_argument("--output", "-o", help="PNG file to write (default: probes.png next to the probe file)")
    p.add_argument("--columns", help="comma-separated probe columns to plot (default: all but the x column)")
    p.add_argument("--x", dest="x_column", default="time", help="x column of the probe file (default: time)")
    p.add_argument("--x-expr", help="expression for the run's x (e.g. 'time*sqrt(2*g/L)'; default: the x column)")
    p.add_argument("--y-expr", help="expression for each plotted run column; `y` is the column (e.g. 'y/L')")
    p.add_argument("--scale-x", type=float, default=1.0, help="factor on the run's x (after --x-expr)")
    p.add_argument("--scale-y", type=float, default=1.0, help="factor on the run's y (after --y-expr)")
    p.add_argument("--const", nargs="+", action="extend", default=[], metavar="NAME=VALUE",
                   help="constants for the expressions, e.g. --const L=0.146 g=9.81 (put it after the probe file)")
    p.add_argument("--reference", help="reference data file (CSV/TSV, '#' comments, header line)")
    p.add_argument("--ref-columns",
                   help="reference columns: x,y[,y2...] (default: the first two columns of the file)")
    p.add_argument("--ref-x-expr", help="expression for the reference x (default: its x column)")
    p.add_argument("--ref-y-expr", help="expression for each reference y; `y` is the column")
    p.add_argument("--ref-target", help="plotted column whose subplot gets the reference (default: the first)")
    p.add_argument("--ref-label", help="legend label of the reference (default: file name and column)")
    p.add_argument("--label", help="legend label of the run (default: 'mpsfsi')")
    p.add_argument("--title", help="figure title (default: the probe file's path and the reference's name; '' for none)")
    p.add_argument("--xlabel", help="x axis label (default: the x expression or 'time [s]')")
    p.add_argument("--ylabel", help="y axis label of every subplot (default: the column name or y expression)")
    p.add_argument("--xlim", help="x range as lo,hi")
    p.add_argument("--size", default="8,0", help="figure width,height in inches (height 0: 2.6 per subplot)")
    p.add_argument("--dpi", type=int, default=120, help="resolution (default 120)")
    return p.parse_args(argv)


def parse_consts(items):
    consts = {}
    for item in items:
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or not name.isidentifier():
            fail(f"--const '{item}': expected NAME=VALUE, e.g. L=0.146")
        try:
            consts[name] = float(value)
        except ValueError:
            fail(f"--const '{item}': '{value}' is not a number")
    return consts


def parse_pair(text, what):
    try:
        a, b = (float(v) for v in text.split(","))
        return a, b
    except ValueError:
        fail(f"{what} '{text}': expected two numbers a,b")


def main(argv=None):
    args = parse_args(argv)
    consts = parse_consts(args.const)

    run = read_table(args.probes)
    names, cols = run
    x_raw = column(run, args.x_column, args.probes)
    if args.columns:
        plotted = [c.strip() for c in args.columns.split(",") if c.strip()]
        if not plotted:
            fail("--columns: no column given")
    else:
        plotted = [n for n in names if n != args.x_column]
        if not plotted:
            fail(f"{args.probes}: no probe columns besides '{args.x_column}'")
    for c in plotted:
        column(run, c, args.probes)

    env = variables(run, consts)
    env["x"] = x_raw
    x = evaluate(args.x_expr, env, "--x-expr") if args.x_expr else x_raw
    x = np.broadcast_to(x, x_raw.shape) * args.scale_x
    series = {}
    for c in plotted:
        env_c = dict(env, y=cols[c])
        y = evaluate(args.y_expr, env_c, "--y-expr") if args.y_expr else cols[c]
        series[c] = np.broadcast_to(y, x_raw.shape) * args.scale_y

    ref = None
    if args.reference:
        table = read_table(args.reference)
        rnames, rcols = table
        if args.ref_columns:
            rc = [c.strip() for c in args.ref_columns.split(",") if c.strip()]
            if len(rc) < 2:
                fail(f"--ref-columns '{args.ref_columns}': expected x,y[,y2...]")
        else:
            if len(rnames) < 2:
                fail(f"{args.reference}: needs at least two columns, has {', '.join(rnames)}")
            rc = rnames[:2]
        for c in rc:
            column(table, c, args.reference)
        renv = variables(table, consts)
        renv["x"] = rcols[rc[0]]
        rx = evaluate(args.ref_x_expr, renv, "--ref-x-expr") if args.ref_x_expr else rcols[rc[0]]
        rx = np.broadcast_to(rx, rcols[rc[0]].shape)
        curves = []
        for c in rc[1:]:
            ry = evaluate(args.ref_y_expr, dict(renv, y=rcols[c]), "--ref-y-expr") if args.ref_y_expr else rcols[c]
            curves.append((c, np.broadcast_to(ry, rx.shape)))
        target = args.ref_target or plotted[0]
        if target not in plotted:
            fail(f"--ref-target '{target}' is not a plotted column; plotted: {', '.join(plotted)}")
        ref = (target, rx, curves, os.path.basename(args.reference))

    # Figure.
    try:
        width, height = (float(v) for v in args.size.split(","))
    except ValueError:
        fail(f"--size '{args.size}': expected width,height in inches")
    n = len(plotted)
    if height <= 0:
        height = 1.0 + 2.6 * n
    plt.rcParams.update({"font.size": 11, "axes.titlesize": 11, "axes.labelsize": 11, "legend.fontsize": 9.5})
    fig, axes = plt.subplots(n, 1, sharex=True, figsize=(width, height), squeeze=False)
    axes = axes[:, 0]
    run_label = args.label or "mpsfsi"
    ref_markers = ["o", "s", "^", "D", "v"]
    for ax, c in zip(axes, plotted):
        ax.plot(x, series[c], "-", color="C0", lw=1.6, label=run_label)
        if ref is not None and ref[0] == c:
            _, rx, curves, rname = ref
            for k, (rcname, ry) in enumerate(curves):
                if len(curves) == 1:
                    label = args.ref_label or f"reference ({rcname})"
                else:
                    label = f"{args.ref_label}: {rcname}" if args.ref_label else rcname
                dense = len(rx) > 40
                ax.plot(rx, ry, ref_markers[k % len(ref_markers)], color=f"C{k + 1}", ms=3.5 if dense else 5.5,
                        mfc="none", mew=1.1 if dense else 1.4, label=label, ls="--" if dense else "none", lw=0.8)
        ax.set_ylabel(args.ylabel or (re.sub(r"\by\b", c, args.y_expr) if args.y_expr else c))
        ax.grid(True, color="0.88", lw=0.7)
        ax.margins(x=0.01)
        if ref is not None and ref[0] == c:
            ax.legend(loc="best", frameon=True, framealpha=0.85, edgecolor="0.8")
    axes[-1].set_xlabel(args.xlabel or (args.x_expr if args.x_expr else
                                        ("time [s]" if args.x_column == "time" else args.x_column)))
    if args.xlim:
        axes[-1].set_xlim(*parse_pair(args.xlim, "--xlim"))
    if args.title is None:
        title = os.path.relpath(args.probes) + (f" against {os.path.basename(args.reference)}" if ref else "")
    else:
        title = args.title
    if title:
        fig.suptitle(title, fontsize=12)
    fig.align_ylabels(axes)
    fig.tight_layout()

    out = args.output or os.path.join(os.path.dirname(os.path.abspath(args.probes)), "probes.png")
    try:
        fig.savefig(out, dpi=args.dpi)
    except OSError as exc:
        fail(f"{out}: cannot write: {exc.strerror}")
    print(f"plot_probes.py: wrote {out} ({n} subplot{'s' if n > 1 else ''}"
          f"{', reference ' + os.path.basename(args.reference) if ref else ''})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
