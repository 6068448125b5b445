#!/usr/bin/env python3
"""Fuzz test of the case-file reader: mutated case files through `mpsfsi check`.

Builds a fixed, reproducible set (seed SEED) of at least 500 mutated case files from the shipped
cases/*.yaml -- wrong types, out-of-range numbers, huge lists, missing / unknown / duplicated keys,
special files for the file keys (a FIFO, /dev/zero, /dev/null, a directory, /etc/passwd, a missing
file, tables with nan rows or non-increasing times), invalid UTF-8, very long names, deep nesting,
alias bombs, empty files and binary garbage -- and runs `mpsfsi check FILE` on each (2 at a time,
20 s timeout each, address space limited to 4 GiB so that a memory-hungry case cannot take the
machine down). Each file must give

  exit 0 with "case OK" on stdout, or
  exit 2 with a message on stderr that starts with "mpsfsi: error:" and names the case file;

never a signal, never exit 1 (internal error), never a timeout, never any other code.
Before the mutations every shipped case (unchanged) must pass with "case OK", so a program that
rejects everything fails too.

Usage:
  fuzz_cases.py MPSFSI CASES_DIR WORK_DIR [--only N[,N...]] [--keep] [--count N] [--jobs J]
                [--timeout S] [--memory-gib G] [--list]

WORK_DIR is emptied first. Failing files stay in WORK_DIR/cases (all files with --keep), and
WORK_DIR/results.tsv lists every file with its result and first line of output. Each failure is
printed with its mutation, exit code or signal and the first lines of output. The last line is
"N passed, N failed"; exit status 0 when nothing failed, 1 otherwise (2 for bad usage).
Registered in ctest as fuzz_case_files (tests/fuzz/CMakeLists.txt, label unit).
"""

import argparse
import concurrent.futures
import copy
import os
import random
import re
import resource
import shutil
import signal
import subprocess
import sys
import time

try:
    import yaml
except ImportError:
    sys.exit("fuzz_cases.py: needs PyYAML (Debian: apt-get install python3-yaml; run it with /usr/bin/python3)")

SEED = 20240613
DEFAULT_COUNT = 520
ERROR_PREFIX = "mpsfsi: error:"  # app/main.cpp prints CaseError messages after this prefix
DUMPER = getattr(yaml, "CSafeDumper", yaml.SafeDumper)  # libyaml's emitter: 10x faster on the huge lists


# ------------------------------------------------------------------------------------------------
# YAML helpers: a tree is what yaml.safe_load gives (dict / list / scalars). Raw scalar text that
# PyYAML would quote or cannot express (1e400, 0x10, .nan spelled differently, aliases, tags) goes in
# as a Raw placeholder and is substituted into the dumped text.


class Raw:
    """A piece of YAML text put into the tree verbatim (as a flow value)."""

    def __init__(self, text):
        self.text = text


def dump(tree):
    """The tree as block-style YAML bytes, Raw values substituted (placeholders are plain words)."""
    raws = []

    def strip(node):
        if isinstance(node, Raw):
            raws.append(node.text)
            return "RAWVALUEPLACEHOLDER%06dX" % (len(raws) - 1)
        if isinstance(node, dict):
            return {strip_key(k): strip(v) for k, v in node.items()}
        if isinstance(node, list):
            return [strip(v) for v in node]
        return node

    def strip_key(key):
        return strip(key) if isinstance(key, Raw) else key

    text = yaml.dump(strip(tree), Dumper=DUMPER, default_flow_style=False, sort_keys=False, allow_unicode=True,
                     width=1 << 30)
    for i, raw in enumerate(raws):
        text = text.replace("RAWVALUEPLACEHOLDER%06dX" % i, raw)
    return text.encode("utf-8", "surrogateescape")


def walk(node, path=()):
    """Every (path, node) of the tree, the root included; a path is a tuple of keys / indices."""
    yield path, node
    if isinstance(node, dict):
        for k, v in node.items():
            yield from walk(v, path + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from walk(v, path + (i,))


def get(tree, path):
    for p in path:
        tree = tree[p]
    return tree


def put(tree, path, value):
    get(tree, path[:-1])[path[-1]] = value


def show_path(path):
    out = ""
    for p in path:
        out += "[%d]" % p if isinstance(p, int) else ("." if out else "") + str(p)
    return out or "(top level)"


def is_number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def set_dotted(tree, dotted, value):
    """Sets a.b.c (creating maps on the way; replaces a non-map on the way by a map)."""
    keys = dotted.split(".")
    node = tree
    for k in keys[:-1]:
        if not isinstance(node.get(k), dict):
            node[k] = {}
        node = node[k]
    node[keys[-1]] = value


# ------------------------------------------------------------------------------------------------
# Values used by the mutations.

BAD_NUMBERS = [Raw("0"), Raw("-1"), Raw("-0.004"), Raw("1e300"), Raw("-1e300"), Raw("1e-300"), Raw("-1e-300"),
               Raw(".nan"), Raw(".NaN"), Raw(".inf"), Raw("-.inf"), Raw("+.inf"), Raw("1e400"), Raw("-1e400"),
               Raw("0x10"), Raw("0o17"), Raw("1_000"), Raw("2147483648"), Raw("-2147483649"),
               Raw("99999999999999999999999"), Raw("1e-12"), Raw("1e12"), Raw("1e6"), Raw("4.9e-324"),
               Raw("1.7976931348623157e308"), Raw(".5"), Raw("5."), Raw("1e"), Raw("--1"), Raw("1.0.0"),
               Raw("nan"), Raw("inf"), Raw("-0"), Raw("1e+"), Raw("0.0000000000000000000000001")]
NOT_NUMBERS = ["abc", "", " ", [1, 2, 3], [], {"a": 1}, {}, True, False, None, Raw('"0.004"'), Raw("'1'"),
               Raw("!!str 1"), Raw("!!float 1"), Raw("!custom 1"), Raw("[[1, 2], [3, 4]]"), Raw("{min: 1}"),
               Raw("~"), Raw("yes"), Raw("0.004 m"), Raw("1,5"), Raw("[.nan, .inf]"), Raw("[1e400, 0]"),
               Raw("[1, 2, 3]"), Raw("[]")]
NUMBER_LIKE = [42, -1, 0, 0.5, Raw("1e300"), Raw(".nan"), Raw("[0, 0]"), Raw("{min: [0, 0], max: [1, 1]}")]

# Optional keys of the schema (docs/case-format.md) that the shipped cases mostly leave out: set to
# bad values, they reach the range checks and the code that uses them (lattice sizes, loops).
KNOWN_KEYS = ["dp", "time.end", "time.dt", "time.cfl", "time.dt_max", "gravity", "domain",
              "fluid.re_gradient", "fluid.re_laplacian", "fluid.beta1", "fluid.beta2", "fluid.gradient",
              "fluid.solver", "fluid.preconditioner", "fluid.tolerance", "fluid.density_tolerance",
              "fluid.max_iterations", "fluid.preconditioner_rebuild_every", "fluid.lateral_walls",
              "fluid.lateral_walls.gap", "fluid.lateral_walls.frequency", "fluid.lateral_walls.model",
              "solid.re", "solid.dt", "solid.plane_stress", "solid.wide_plate", "solid.dt_factor",
              "solid.contact_stiffness", "solid.normalisation", "solid.volumetric_strain",
              "coupling.subcycles", "coupling.solid_damping", "coupling.load_relaxation",
              "output.interval", "output.fields", "receivers.interval", "receivers.radius", "receivers.points",
              "tank_motion.type", "tank_motion.pivot", "tank_motion.amplitude_deg", "tank_motion.period",
              "tank_motion.file", "probes", "walls", "bodies", "materials", "solid_loads", "sources"]
# Keys whose large values make the program build big lattices (memory, time).
SIZE_KEYS = {"dp": [Raw("1e-5"), Raw("2e-5"), Raw("2e-6"), Raw("1e-7"), Raw("1e-9"), Raw("1e-300"), Raw("3e-5"), Raw("1e-4")],
             "fluid.re_laplacian": [Raw("1e300"), Raw("1e9"), Raw("1e6"), Raw("1e4"), Raw("1000"), Raw("1.7e308")],
             "fluid.re_gradient": [Raw("1e300"), Raw("1e9"), Raw("1e6"), Raw("1e4")],
             "solid.re": [Raw("1e300"), Raw("1e9"), Raw("1e6"), Raw("1e4"), Raw("1000")],
             "receivers.radius": [Raw("1e300"), Raw("1e6")],
             "output.interval": [Raw("1e-300"), Raw("4.9e-324")],
             "time.dt": [Raw("1e-300"), Raw("4.9e-324")]}


def pick_path(tree, rng, want):
    """A random non-root path whose node satisfies want(node), or None."""
    paths = [p for p, n in walk(tree) if p and want(n)]
    return rng.choice(paths) if paths else None


# ------------------------------------------------------------------------------------------------
# Mutations. Each takes (ctx, tree, rng), may change the tree and returns (description, bytes or None);
# None means "dump the tree".


def m_number_wrong_type(ctx, tree, rng):
    path = pick_path(tree, rng, is_number)
    if path is None:
        return m_known_key_bad_value(ctx, tree, rng)
    value = rng.choice(NOT_NUMBERS)
    put(tree, path, copy.deepcopy(value))
    return "number %s replaced by %s" % (show_path(path), describe(value)), None


def m_other_wrong_type(ctx, tree, rng):
    path = pick_path(tree, rng, lambda n: not is_number(n))
    value = rng.choice(NUMBER_LIKE)
    put(tree, path, copy.deepcopy(value))
    return "value %s replaced by %s" % (show_path(path), describe(value)), None


def m_bad_number(ctx, tree, rng):
    path = pick_path(tree, rng, is_number)
    if path is None:
        return m_known_key_bad_value(ctx, tree, rng)
    value = rng.choice(BAD_NUMBERS)
    put(tree, path, value)
    return "number %s set to %s" % (show_path(path), describe(value)), None


def m_known_key_bad_value(ctx, tree, rng):
    key = rng.choice(KNOWN_KEYS)
    value = rng.choice(BAD_NUMBERS + NOT_NUMBERS)
    set_dotted(tree, key, copy.deepcopy(value))
    return "%s set to %s" % (key, describe(value)), None


def next_of(ctx, name, options):
    """The options in turn (every one is used once before any is used twice); build() is sequential, so the
    choice is reproducible."""
    n = ctx.setdefault(name, 0)
    ctx[name] = n + 1
    return options[n % len(options)]


SIZE_PAIRS = [(key, value) for key in sorted(SIZE_KEYS) for value in SIZE_KEYS[key]]


def m_size_key(ctx, tree, rng):
    key, value = next_of(ctx, "size_pairs", SIZE_PAIRS)
    set_dotted(tree, key, value)
    return "%s set to %s (large lattice / many steps)" % (key, describe(value)), None


def flow(value):
    """A value as one line of flow-style YAML."""
    return yaml.dump(value, Dumper=DUMPER, default_flow_style=True, width=1 << 30).strip().removesuffix("...").strip()


def m_huge_list(ctx, tree, rng):
    # Written as flow text (Raw): building the tree and dumping it would take seconds per file.
    n = rng.choice([10000, 50000, 100000])
    variant = rng.randrange(6)
    if variant == 0:
        path = pick_path(tree, rng, lambda v: isinstance(v, list) and v and not any(isinstance(x, Raw) for x in v))
        if path is not None:
            item = flow(get(tree, path)[0])
            put(tree, path, Raw("[" + ", ".join([item] * n) + "]"))
            return "list %s repeated to %d items" % (show_path(path), n), None
        variant = 1
    if variant == 1:
        set_dotted(tree, "output.fields", Raw("[" + ", ".join("field%d" % i for i in range(n)) + "]"))
        return "output.fields: %d distinct names" % n, None
    if variant == 2:
        lo, hi = tree.get("domain", {}).get("min", [0, 0]), tree.get("domain", {}).get("max", [1, 1])
        x = (lo[0] + hi[0]) / 2 if all(map(is_number, lo + hi)) else 0
        y = (lo[1] + hi[1]) / 2 if all(map(is_number, lo + hi)) else 0
        tree["probes"] = Raw("[" + ", ".join("{name: p%d, type: pressure, position: [%r, %r]}" % (i, x, y)
                                             for i in range(n)) + "]")
        return "probes: %d distinct pressure probes" % n, None
    if variant == 3:
        tree["gravity"] = Raw("[" + ", ".join(["0.0"] * n) + "]")
        return "gravity: a vector of %d numbers" % n, None
    if variant == 4:
        tree["walls"] = Raw("[" + ", ".join("{name: w%d, type: block, rectangle: {min: [0, 0], max: [1, 1]}}" % i
                                            for i in range(n // 10)) + "]")
        return "walls: %d block walls" % (n // 10), None
    tree["materials"] = Raw("{" + ", ".join("m%d: {type: fluid, rho: 1000, nu: 1.0e-6}" % i for i in range(n // 10)) + "}")
    return "materials: %d fluid materials" % (n // 10), None


def m_delete_key(ctx, tree, rng):
    path = pick_path(tree, rng, lambda v: True) if rng.random() < 0.7 else None
    if path is None or not isinstance(get(tree, path[:-1]), dict):
        # A top-level or a required key.
        key = rng.choice(list(tree.keys()))
        del tree[key]
        return "top-level key %s deleted" % key, None
    del get(tree, path[:-1])[path[-1]]
    return "key %s deleted" % show_path(path), None


def m_unknown_key(ctx, tree, rng):
    path = pick_path(tree, rng, lambda v: isinstance(v, dict))
    target = tree if path is None or rng.random() < 0.2 else get(tree, path)
    existing = [k for k in target.keys() if isinstance(k, str) and len(k) > 2]
    if existing and rng.random() < 0.5:
        k = rng.choice(existing)
        i = rng.randrange(len(k) - 1)
        key = k[:i] + k[i + 1] + k[i] + k[i + 2:]  # a typo: two letters swapped
    else:
        key = rng.choice(["colour", "zz_unknown", "Name", "DP", "tme", "bodys", "extra", "_", "1", "null"])
    if key in target:
        key += "_x"
    target[key] = rng.choice([1, "x", [1, 2], {"a": 1}, None])
    return "unknown key '%s' added in %s" % (key, show_path(path) if target is not tree else "(top level)"), None


def m_duplicate_key(ctx, tree, rng):
    lines = dump(tree).decode("utf-8", "surrogateescape").split("\n")
    candidates = [i for i, line in enumerate(lines) if re.match(r"^\s*(- )?[A-Za-z_][\w-]*:( |$)", line)]
    i = rng.choice(candidates)
    line = lines[i]
    dup = line.replace("- ", "  ", 1) if line.lstrip().startswith("- ") else line
    if line.rstrip().endswith(":") and not line.lstrip().startswith("- "):
        # A key with a block value: the same key with a scalar value just before it.
        lines.insert(i, dup.rstrip() + " 1")
    else:
        lines.insert(i + 1, dup)
    return "key line %d '%s' duplicated" % (i + 1, dup.strip()[:60]), "\n".join(lines).encode("utf-8")


def m_special_file(ctx, tree, rng):
    # Every special file for both file keys in turn.
    pairs = [(key, item) for item in sorted(ctx["special"].items()) for key in ("tank_motion", "wavelet")]
    key, (name, path) = next_of(ctx, "special_pairs", pairs)
    if key == "tank_motion":
        tree["tank_motion"] = {"type": "table", "pivot": [0, 0], "file": path}
        if not tree.get("walls"):
            tree["walls"] = [{"name": "tank_fuzz", "type": "box",
                              "rectangle": {"min": [-1e3, -1e3], "max": [1e3, 1e3]}, "open_top": True}]
        return "tank_motion.file = %s (%s)" % (path, name), None
    solids = [b for b in tree.get("bodies", []) if isinstance(b, dict) and b.get("kind") == "solid"]
    if solids:
        b = solids[0]
        rect = b.get("rectangle", {})
        lo, hi = rect.get("min", [0, 0]), rect.get("max", [0, 0])
        pos = [(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2]
        body = b.get("name")
    else:
        pos, body = [0, 0], "nosuchbody"
    tree["sources"] = [{"name": "fuzz", "body": body, "type": "explosion", "position": pos, "amplitude": 1.0,
                        "wavelet": {"type": "table", "file": path}}]
    return "sources[0].wavelet.file = %s (%s)" % (path, name), None


def m_invalid_utf8(ctx, tree, rng):
    bad = rng.choice([b"\xff\xfe", b"\xc3\x28", b"\xe2\x82", b"\xed\xa0\x80", b"\x80abc", b"\xf8\x88\x80\x80\x80"])
    where = rng.randrange(5)
    text = dump(tree)
    if where == 0:
        tree["description"] = Raw("DESCRIPTIONUTF8X")
        text = dump(tree).replace(b"DESCRIPTIONUTF8X", b'"water ' + bad + b' column"')
        return "description with invalid UTF-8 %r" % bad, text
    if where == 1:
        tree["name"] = Raw("NAMEUTF8X")
        text = dump(tree).replace(b"NAMEUTF8X", b"case" + bad)
        return "name with invalid UTF-8 %r" % bad, text
    if where == 2:
        return "comment with invalid UTF-8 %r" % bad, b"# " + bad + b"\n" + text
    if where == 3:
        return "top-level key with invalid UTF-8 %r" % bad, text + b"key" + bad + b": 1\n"
    mats = tree.get("materials")
    if isinstance(mats, dict) and mats:
        first = next(iter(mats))
        mats["MATUTF8X"] = mats.pop(first)
        return "material name with invalid UTF-8 %r" % bad, dump(tree).replace(b"MATUTF8X", b"mat" + bad)
    return "BOM and invalid UTF-8 after it", b"\xef\xbb\xbf" + bad + text


def m_long_name(ctx, tree, rng):
    n = rng.choice([1000, 100000, 1000000])
    variant = rng.randrange(5)
    if variant == 0:
        tree["name"] = "a" * n
        return "name of %d letters" % n, None
    if variant == 1:
        tree["description"] = "d" * n
        return "description of %d characters" % n, None
    if variant == 2:
        bodies = tree.get("bodies")
        if isinstance(bodies, list) and bodies and isinstance(bodies[0], dict):
            bodies[0]["name"] = "b" * n
            return "bodies[0].name of %d letters" % n, None
    if variant == 3:
        tree["k" * n] = 1
        return "unknown top-level key of %d letters" % n, None
    tree["name"] = "x" * (n - 1) + "."
    return "name of %d characters ending with '.'" % n, None


def m_deep_nesting(ctx, tree, rng):
    depth = rng.choice([100, 1000, 10000, 100000])
    key = rng.choice(["description", "gravity", "domain", "bodies", "zz_unknown", "time"])
    style = rng.randrange(3)
    if style == 0:
        value = "[" * depth + "1" + "]" * depth
    elif style == 1:
        value = "{a: " * depth + "1" + "}" * depth
    else:
        value = "[" * depth  # unterminated
    tree[key] = Raw(value)
    return "%s = %s nested %d deep" % (key, ["[[...]]", "{a: {a: ...}}", "unterminated [[["][style], depth), None


def m_block_nesting(ctx, tree, rng):
    depth = rng.choice([100, 1000, 5000])
    lines = ["zz_deep:"] + ["  " * (i + 1) + "a:" for i in range(depth)]
    return "unknown key with block maps nested %d deep" % depth, dump(tree) + ("\n".join(lines) + " 1\n").encode()


def m_alias_bomb(ctx, tree, rng):
    levels = rng.choice([6, 9])
    key = rng.choice(["gravity", "domain", "description", "bodies", "zz_unknown", "dp", "materials"])
    parts = ['&l0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
    for i in range(1, levels):
        parts.append("&l%d [%s]" % (i, ", ".join(["*l%d" % (i - 1)] * 10)))
    tree[key] = Raw("[" + ", ".join(parts) + "]")
    return "%s = alias bomb (10^%d elements when expanded)" % (key, levels), None


def m_yaml_feature(ctx, tree, rng):
    text = dump(tree)
    variant = rng.randrange(12)
    extras = [
        ("second YAML document", text + b"---\nname: again\n"),
        ("tab indentation", text.replace(b"\n  ", b"\n\t", 1)),
        ("merge key <<", text + b"zz_base: &b {x: 1}\nzz_merged:\n  <<: *b\n"),
        ("complex key ? [a, b]", text + b"? [a, b]\n: 1\n"),
        ("null key", text + b"~: 1\n"),
        ("unknown tag on dp", text.replace(b"\ndp: ", b"\ndp: !custom ", 1)),
        ("!!binary value", text + b"zz_bin: !!binary aGVsbG8=\n"),
        ("undefined alias", text + b"zz: *nosuch\n"),
        ("document end marker only", b"...\n" + text),
        ("NUL byte in the middle", text[: len(text) // 2] + b"\x00" + text[len(text) // 2:]),
        ("CR line ends", text.replace(b"\n", b"\r")),
        ("a list at the top level", b"- " + text.replace(b"\n", b"\n  ")),
    ]
    description, data = extras[variant]
    return description, data


def m_empty(ctx, tree, rng):
    options = [b"", b"\n", b"# only a comment\n", b"   \n\n", b"---\n", b"~\n", b"[]\n", b"{}\n", b"42\n",
               b"---\n---\n", b"...\n", b"\xef\xbb\xbf", b"null", b"name:\n", b"''\n"]
    data = rng.choice(options)
    return "empty or trivial file %r" % data, data


def m_garbage(ctx, tree, rng):
    n = rng.choice([1, 16, 256, 4096, 65536])
    garbage = bytes(rng.randrange(256) for _ in range(n))
    variant = rng.randrange(3)
    if variant == 0:
        return "%d bytes of binary garbage" % n, garbage
    text = dump(tree)
    if variant == 1:
        return "valid case followed by %d bytes of garbage" % n, text + garbage
    cut = rng.randrange(len(text))
    return "case truncated at byte %d plus %d bytes of garbage" % (cut, n), text[:cut] + garbage


def m_truncated(ctx, tree, rng):
    text = dump(tree)
    cut = rng.randrange(1, len(text))
    return "case truncated at byte %d of %d" % (cut, len(text)), text[:cut]


def m_geometry(ctx, tree, rng):
    """Rectangles turned inside out, moved out of the domain, bodies on top of each other."""
    rects = [p for p, n in walk(tree) if isinstance(n, dict) and "min" in n and "max" in n]
    if not rects:
        return m_bad_number(ctx, tree, rng)
    path = rng.choice(rects)
    r = get(tree, path)
    variant = rng.randrange(6)
    if variant == 0:
        r["min"], r["max"] = r["max"], r["min"]
        return "%s: min and max swapped" % show_path(path), None
    if variant == 1:
        r["max"] = copy.deepcopy(r["min"])
        return "%s: max = min (empty rectangle)" % show_path(path), None
    if variant == 2:
        r["min"], r["max"] = [-1e300, -1e300], [1e300, 1e300]
        return "%s = {min: [-1e300, -1e300], max: [1e300, 1e300]}" % show_path(path), None
    if variant == 3:
        r["min"], r["max"] = [1e6, 1e6], [1e6 + 1, 1e6 + 1]
        return "%s moved far outside the domain" % show_path(path), None
    if variant == 4:
        r["max"] = [Raw(".inf"), Raw(".inf")]
        return "%s.max = [.inf, .inf]" % show_path(path), None
    bodies = tree.get("bodies")
    if isinstance(bodies, list) and bodies:
        bodies.append(copy.deepcopy(bodies[0]))
        bodies[-1]["name"] = "copy_of_first"
        return "bodies[0] duplicated under another name (overlap)", None
    return "%s: min and max swapped" % show_path(path), None


MUTATIONS = [
    ("number_wrong_type", m_number_wrong_type),
    ("other_wrong_type", m_other_wrong_type),
    ("bad_number", m_bad_number),
    ("known_key_bad_value", m_known_key_bad_value),
    ("size_key", m_size_key),
    ("huge_list", m_huge_list),
    ("delete_key", m_delete_key),
    ("unknown_key", m_unknown_key),
    ("duplicate_key", m_duplicate_key),
    ("special_file", m_special_file),
    ("invalid_utf8", m_invalid_utf8),
    ("long_name", m_long_name),
    ("deep_nesting", m_deep_nesting),
    ("block_nesting", m_block_nesting),
    ("alias_bomb", m_alias_bomb),
    ("yaml_feature", m_yaml_feature),
    ("empty", m_empty),
    ("garbage", m_garbage),
    ("truncated", m_truncated),
    ("geometry", m_geometry),
    # The most common kinds of user error get more files.
    ("bad_number", m_bad_number),
    ("number_wrong_type", m_number_wrong_type),
    ("known_key_bad_value", m_known_key_bad_value),
    ("special_file", m_special_file),
    ("delete_key", m_delete_key),
    ("size_key", m_size_key),
    ("special_file", m_special_file),
]


def describe(value):
    if isinstance(value, Raw):
        return value.text
    return repr(value)


# ------------------------------------------------------------------------------------------------
# Building the files.


def load_cases(cases_dir):
    """(name, tree) of every cases/*.yaml, relative file keys made absolute (the mutated files live elsewhere)."""
    cases = []
    for name in sorted(os.listdir(cases_dir)):
        if not name.endswith(".yaml"):
            continue
        with open(os.path.join(cases_dir, name), encoding="utf-8") as f:
            tree = yaml.safe_load(f)
        tm = tree.get("tank_motion")
        if isinstance(tm, dict) and isinstance(tm.get("file"), str) and not os.path.isabs(tm["file"]):
            tm["file"] = os.path.abspath(os.path.join(cases_dir, tm["file"]))
        for s in tree.get("sources", []) or []:
            w = s.get("wavelet", {})
            if isinstance(w.get("file"), str) and not os.path.isabs(w["file"]):
                w["file"] = os.path.abspath(os.path.join(cases_dir, w["file"]))
        for item in (tree.get("bodies", []) or []) + (tree.get("walls", []) or []):
            for key in ("polygon", "surface"):
                shape = item.get(key) if isinstance(item, dict) else None
                if isinstance(shape, dict) and isinstance(shape.get("file"), str) and not os.path.isabs(shape["file"]):
                    shape["file"] = os.path.abspath(os.path.join(cases_dir, shape["file"]))
        cases.append((name, tree))
    return cases


def make_special_files(folder):
    """The special files for the file keys; returns name -> path."""
    os.makedirs(folder, exist_ok=True)
    fifo = os.path.join(folder, "fifo")
    os.mkfifo(fifo)
    directory = os.path.join(folder, "a_directory")
    os.mkdir(directory)
    files = {
        "nan_rows.csv": "time,value\n0,0\n0.1,nan\n0.2,1\n",
        "nan_time.csv": "0,0\nnan,1\n0.2,1\n",
        "inf_rows.csv": "0,0\n0.1,inf\n0.2,1e400\n",
        "non_increasing.csv": "0,0\n0.2,1\n0.1,2\n",
        "repeated_time.csv": "0,0\n0.1,1\n0.1,2\n",
        "one_row.csv": "0,0\n",
        "empty.csv": "",
        "header_only.csv": "time,value\n",
        "three_columns.csv": "0,0,0\n1,1,1\n",
        "text.csv": "a,b\nc,d\n",
        "crlf.csv": "0,0\r\n1,1\r\n",
        "long_line.csv": "0," + "1" * 1000000 + "\n1,1\n",
    }
    out = {"fifo (no writer)": fifo, "directory": directory, "/dev/zero": "/dev/zero", "/dev/null": "/dev/null",
           "/etc/passwd": "/etc/passwd", "missing file": os.path.join(folder, "no_such_file.csv"),
           "/proc/self/mem": "/proc/self/mem", "/dev/urandom": "/dev/urandom"}
    for name, text in files.items():
        path = os.path.join(folder, name)
        with open(path, "w") as f:
            f.write(text)
        out[name] = path
    binary = os.path.join(folder, "binary.csv")
    with open(binary, "wb") as f:
        f.write(bytes(random.Random(SEED).randrange(256) for _ in range(65536)))
    out["binary.csv"] = binary
    unreadable = os.path.join(folder, "unreadable.csv")
    with open(unreadable, "w") as f:
        f.write("0,0\n1,1\n")
    os.chmod(unreadable, 0)
    out["unreadable.csv (mode 000)"] = unreadable
    return out


def build(cases, count, ctx):
    """The list of (index, case name, kind, description, bytes), reproducible from SEED."""
    items = []
    for i in range(count):
        rng = random.Random("%d-%d" % (SEED, i))
        case_name, tree = cases[i % len(cases)]
        kind, mutate = MUTATIONS[(i // len(cases) + i) % len(MUTATIONS)]
        tree = copy.deepcopy(tree)
        description, data = mutate(ctx, tree, rng)
        if data is None:
            data = dump(tree)
        items.append((i, case_name, kind, description, data))
    return items


# ------------------------------------------------------------------------------------------------
# Running.


def set_memory_limit(gib):
    """Limits this process's address space; the children (mpsfsi) inherit the limit. Done here, not in a
    preexec_fn, which is unsafe with the worker threads."""
    limit = int(gib * (1 << 30))
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    if hard != resource.RLIM_INFINITY:
        limit = min(limit, hard)
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))


def run_check(mpsfsi, path, timeout):
    """(outcome, code, stdout, stderr, seconds); outcome is 'exit', 'signal' or 'timeout'."""
    start = time.monotonic()
    # One process: Open MPI needs only its "self" transport (starts ~30 % faster than probing the others).
    env = dict(os.environ, OMPI_MCA_btl="self", OMPI_MCA_pml="ob1")
    proc = subprocess.Popen([mpsfsi, "check", path], stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, start_new_session=True, env=env)
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        out, err = proc.communicate()
        return "timeout", None, out, err, time.monotonic() - start
    seconds = time.monotonic() - start
    if proc.returncode < 0:
        return "signal", -proc.returncode, out, err, seconds
    return "exit", proc.returncode, out, err, seconds


def judge(path, outcome, code, out, err, timeout):
    """None if the result is acceptable, else the reason."""
    stdout = out.decode("utf-8", "replace")
    stderr = err.decode("utf-8", "replace")
    if outcome == "timeout":
        return "timeout after %g s" % timeout
    if outcome == "signal":
        try:
            name = signal.Signals(code).name
        except ValueError:
            name = str(code)
        return "killed by signal %s" % name
    if code == 0:
        return None if "case OK" in stdout else "exit 0 without 'case OK'"
    if code == 2:
        if not stderr.startswith(ERROR_PREFIX):
            return "exit 2 but stderr does not start with '%s'" % ERROR_PREFIX
        first = stderr.split("\n", 1)[0]
        if os.path.basename(path) not in first:
            return "exit 2 but the message does not name the case file"
        return None
    return "exit %d" % code


def first_lines(data, n=4, width=300):
    lines = data.decode("utf-8", "replace").splitlines()[:n]
    return [line if len(line) <= width else line[:width] + "... (%d chars)" % len(line) for line in lines]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("mpsfsi", help="the mpsfsi program")
    parser.add_argument("cases_dir", help="the folder of the shipped cases (cases/)")
    parser.add_argument("work_dir", help="work folder (emptied first); failing files are kept in WORK_DIR/cases")
    parser.add_argument("--only", help="run only these files: N or N,M,... (indices as printed)")
    parser.add_argument("--keep", action="store_true", help="keep every file, not only the failing ones")
    parser.add_argument("--count", type=int, default=DEFAULT_COUNT, help="number of mutated files (default %(default)s)")
    parser.add_argument("--jobs", type=int, default=2, help="files checked at the same time (default %(default)s)")
    parser.add_argument("--timeout", type=float, default=20, help="seconds per file (default %(default)s)")
    parser.add_argument("--memory-gib", type=float, default=4, help="address-space limit per check (default %(default)s)")
    parser.add_argument("--list", action="store_true", help="only list the mutations, run nothing")
    args = parser.parse_args()

    if not os.access(args.mpsfsi, os.X_OK):
        print("fuzz_cases.py: %s: not an executable program" % args.mpsfsi, file=sys.stderr)
        return 2
    if args.count < 500 and args.only is None and not args.list:
        print("fuzz_cases.py: --count %d: expected at least 500" % args.count, file=sys.stderr)
        return 2
    only = None
    if args.only is not None:
        try:
            only = {int(x) for x in args.only.split(",")}
        except ValueError:
            print("fuzz_cases.py: --only %s: expected N or N,M,..." % args.only, file=sys.stderr)
            return 2

    started = time.monotonic()
    shutil.rmtree(args.work_dir, ignore_errors=True)
    case_dir = os.path.join(args.work_dir, "cases")
    os.makedirs(case_dir)
    ctx = {"special": make_special_files(os.path.join(args.work_dir, "special"))}
    cases = load_cases(args.cases_dir)
    if not cases:
        print("fuzz_cases.py: %s: no *.yaml case files" % args.cases_dir, file=sys.stderr)
        return 2
    count = max(args.count, 1 + max(only)) if only else args.count
    items = build(cases, count, ctx)
    if args.list:
        for i, case_name, kind, description, data in items:
            print("%04d %-28s %-20s %s" % (i, case_name, kind, description))
        return 0

    # The jobs: the unchanged shipped cases (must pass with "case OK"), then the mutations.
    jobs = []
    if only is None:
        for name, tree in cases:
            path = os.path.join(case_dir, "base_" + name)
            with open(path, "wb") as f:
                f.write(dump(tree))
            jobs.append(("base", name, "unchanged", "shipped case, must give 'case OK'", path))
    for i, case_name, kind, description, data in items:
        if only is not None and i not in only:
            continue
        path = os.path.join(case_dir, "%04d_%s_%s.yaml" % (i, case_name[:-5], kind))
        with open(path, "wb") as f:
            f.write(data)
        jobs.append(("%04d" % i, case_name, kind, description, path))

    set_memory_limit(args.memory_gib)
    results = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        futures = {pool.submit(run_check, args.mpsfsi, job[4], args.timeout): job for job in jobs}
        for future in concurrent.futures.as_completed(futures):
            job = futures[future]
            outcome, code, out, err, seconds = future.result()
            reason = judge(job[4], outcome, code, out, err, args.timeout)
            if job[0] == "base" and reason is None and not (outcome == "exit" and code == 0):
                reason = "shipped case rejected (exit %s)" % code
            results.append((job, outcome, code, out, err, seconds, reason))

    results.sort(key=lambda r: r[0][4])
    failed = [r for r in results if r[6] is not None]
    # Every result in one table (kept in WORK_DIR), for a look at the messages of the files that passed.
    with open(os.path.join(args.work_dir, "results.tsv"), "w", encoding="utf-8") as table:
        table.write("file\tcase\tkind\tmutation\tresult\tseconds\tfirst line of output\n")
        for job, outcome, code, out, err, seconds, reason in results:
            line = (first_lines(err, 1) or first_lines(out, 1) or [""])[0]
            result = reason or ("exit %s" % code)
            table.write("\t".join([os.path.basename(job[4]), job[1], job[2], job[3], result, "%.2f" % seconds,
                                    line.replace("\t", " ")]) + "\n")
    for job, outcome, code, out, err, seconds, reason in failed:
        tag, case_name, kind, description, path = job
        print("FAIL %s %s [%s] %s" % (tag, case_name, kind, description))
        print("     %s (%.1f s); file %s" % (reason, seconds, path))
        for line in first_lines(err) or first_lines(out) or ["(no output)"]:
            print("     | " + line)
    for job, outcome, code, out, err, seconds, reason in results:
        if reason is None and not args.keep:
            os.remove(job[4])
    accepted = sum(1 for r in results if r[6] is None and r[1] == "exit" and r[2] == 0)
    slowest = max(results, key=lambda r: r[5]) if results else None
    print("checked %d files (%d shipped cases unchanged, %d mutated) in %.0f s; %d accepted with 'case OK'%s"
          % (len(results), sum(1 for r in results if r[0][0] == "base"), sum(1 for r in results if r[0][0] != "base"),
             time.monotonic() - started, accepted,
             "; slowest %s %.1f s" % (os.path.basename(slowest[0][4]), slowest[5]) if slowest else ""))
    print("%d passed, %d failed" % (len(results) - len(failed), len(failed)))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
