#!/usr/bin/env python3
"""Checks that docs/ARCHITECTURE.md tells the truth about the CMake target graph.

Compares, and prints every difference:
  1. the "target graph" block of the document (layer, folder, target -> direct dependencies)
     with the graph CMake configured (build/architecture/target_graph.tsv, written by
     cmake/HandshareTargetGraph.cmake): the same targets, folders and edges;
  2. the layers: every documented dependency points to a lower layer, or to the same layer in
     the same folder (a row of the "Folders and targets" table);
  3. the "Folders and targets" table: each row's "layer" cell lists the layers of the row's
     targets, and the project libraries named in its "depends on" cell are the ones its
     targets link from other rows.

usage: check_target_graph.py --doc docs/ARCHITECTURE.md --graph BUILD/architecture/target_graph.tsv
Exit status 0 when they agree, 1 with the differences on stdout, 2 when a file cannot be read.
"""
import argparse
import re
import sys

MARKER = "# target graph"
TABLE_HEADING = "### Folders and targets"


class ParseError(Exception):
    pass


def read_graph(path):
    """CMake's graph: {target: (type, folder, deps)} and the options it was configured with."""
    targets, options = {}, {}
    with open(path) as f:
        for number, line in enumerate(f, 1):
            line = line.rstrip("\n")
            if not line:
                continue
            m = re.match(r"# option (\w+)=(.*)$", line)
            if m:
                options[m.group(1)] = m.group(2).upper() in ("ON", "1", "TRUE", "YES", "Y")
                continue
            if line.startswith("#"):
                continue
            fields = line.split("\t")
            if len(fields) != 4:
                raise ParseError(f"{path}:{number}: expected 4 tab-separated fields: {line!r}")
            name, kind, folder, deps = fields
            targets[name] = (kind, folder, set(d for d in deps.split(";") if d))
    return targets, options


def read_doc_block(lines, path):
    """The documented graph: {target: (layer, folder, deps, line number)}."""
    start = None
    for i, line in enumerate(lines):
        if line.strip().lower().startswith(MARKER) and i > 0:
            # The marker is the first line inside a fenced block.
            if lines[i - 1].strip().startswith("```"):
                start = i
                break
    if start is None:
        raise ParseError(f"{path}: no fenced block starting with '{MARKER}'")
    documented = {}
    for i in range(start, len(lines)):
        line = lines[i].strip()
        if line.startswith("```"):
            return documented
        if not line or line.startswith("#"):
            continue
        if "->" not in line:
            raise ParseError(f"{path}:{i + 1}: expected 'layer folder target -> deps': {line!r}")
        left, right = line.split("->", 1)
        head = left.split()
        if len(head) != 3 or not head[0].isdigit():
            raise ParseError(f"{path}:{i + 1}: expected 'layer folder target' before '->': {line!r}")
        layer, folder, target = int(head[0]), head[1], head[2]
        if target in documented:
            raise ParseError(f"{path}:{i + 1}: {target} is listed twice")
        deps = set(d for d in re.split(r"[,\s]+", right.strip()) if d)
        documented[target] = (layer, folder, deps, i + 1)
    raise ParseError(f"{path}: the target graph block is not closed")


def read_doc_table(lines, path):
    """The "Folders and targets" table: [(folder, layer cell, depends-on cell, line number)]."""
    try:
        start = next(i for i, l in enumerate(lines) if l.startswith(TABLE_HEADING))
    except StopIteration:
        raise ParseError(f"{path}: no section '{TABLE_HEADING}'")
    rows, header = [], None
    for i in range(start + 1, len(lines)):
        line = lines[i].strip()
        if not line.startswith("|"):
            if rows or header:
                break
            continue
        cells = [c.strip() for c in line.strip("|").split("|")]
        if header is None:
            header = [c.lower() for c in cells]
            for need in ("folder", "layer", "depends on"):
                if need not in header:
                    raise ParseError(f"{path}:{i + 1}: the table has no column '{need}'")
            continue
        if set(line.replace("|", "").strip()) <= set("-: "):
            continue  # the separator row
        if len(cells) != len(header):
            raise ParseError(f"{path}:{i + 1}: {len(cells)} cells, the header has {len(header)}")
        row = dict(zip(header, cells))
        rows.append((row["folder"].strip("`"), row["layer"], row["depends on"], i + 1))
    return rows


def short(name):
    return name[len("handshare::"):] if name.startswith("handshare::") else name


def layer_numbers(cell):
    numbers = set()
    for a, b in re.findall(r"(\d+)(?:\s*-\s*(\d+))?", cell):
        numbers.update(range(int(a), int(b or a) + 1))
    return numbers


def row_of(folder, rows):
    """The table row a source folder belongs to: the longest row folder that contains it."""
    best = None
    for r in rows:
        f = r[0]
        if folder == f or folder.startswith(f + "/"):
            if best is None or len(f) > len(best[0]):
                best = r
    return best


def check(doc_path, graph_path):
    with open(doc_path) as f:
        lines = f.read().split("\n")
    built, options = read_graph(graph_path)
    documented = read_doc_block(lines, doc_path)
    rows = read_doc_table(lines, doc_path)
    problems = []

    # 1. Targets, folders and edges.
    bench_off = options.get("HANDSHARE_BUILD_BENCH") is False
    for t in sorted(set(built) - set(documented)):
        kind, folder, deps = built[t]
        problems.append(f"target {t} ({kind} in {folder}) is built but not in the document's graph; "
                        f"it links: {', '.join(sorted(deps)) or 'nothing of the project'}")
    for t in sorted(set(documented) - set(built)):
        layer, folder, deps, line = documented[t]
        if bench_off and (folder == "bench" or folder.startswith("bench/")):
            continue  # configured with HANDSHARE_BUILD_BENCH=OFF
        problems.append(f"{doc_path}:{line}: target {t} is documented but CMake has no such target")
    for t in sorted(set(built) & set(documented)):
        kind, folder, deps = built[t]
        layer, doc_folder, doc_deps, line = documented[t]
        if folder != doc_folder:
            problems.append(f"{doc_path}:{line}: {t} is in {folder}, the document says {doc_folder}")
        for d in sorted(deps - doc_deps):
            problems.append(f"{doc_path}:{line}: edge {t} -> {d} is in CMake but not in the document")
        for d in sorted(doc_deps - deps):
            problems.append(f"{doc_path}:{line}: edge {t} -> {d} is in the document but not in CMake")

    # 2. Layers: dependencies point down (or stay in their folder's row of the table).
    for t, (layer, folder, deps, line) in sorted(documented.items()):
        row = row_of(folder, rows)
        if row is None:
            problems.append(f"{doc_path}:{line}: {t}: folder {folder} has no row in the table")
        for d in sorted(deps):
            if d not in documented:
                if d not in built:
                    problems.append(f"{doc_path}:{line}: {t} -> {d}: {d} is no target")
                continue
            d_layer, d_folder, _, _ = documented[d]
            same_row = row is not None and row_of(d_folder, rows) is row
            if d_layer > layer or (d_layer == layer and not same_row):
                problems.append(f"{doc_path}:{line}: {t} (layer {layer}, {folder}) -> {d} (layer {d_layer}, "
                                f"{d_folder}) does not point to a lower layer")

    # 3. The table's "layer" and "depends on" cells.
    libraries = {short(t) for t, (kind, _, _) in built.items() if kind.endswith("LIBRARY")}
    for folder, layer_cell, deps_cell, line in rows:
        members = {t: v for t, v in documented.items() if row_of(v[1], rows) is not None
                   and row_of(v[1], rows)[0] == folder}
        want_layers = {v[0] for v in members.values()}
        if layer_numbers(layer_cell) != want_layers:
            problems.append(f"{doc_path}:{line}: row {folder}: layer '{layer_cell}', its targets are in "
                            f"{', '.join(map(str, sorted(want_layers))) or 'no layer'}")
        outside = set()
        for t, (_, _, deps, _) in members.items():
            outside |= {short(d) for d in deps if d not in members}
        named = {short(tok) for tok in re.findall(r"[A-Za-z_][A-Za-z0-9_:]*", deps_cell)} & libraries
        for d in sorted(outside - named):
            problems.append(f"{doc_path}:{line}: row {folder}: 'depends on' does not name {d}, which its targets link")
        for d in sorted(named - outside):
            problems.append(f"{doc_path}:{line}: row {folder}: 'depends on' names {d}, which none of its targets links")
    return problems, len(built), len(documented)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--doc", required=True)
    parser.add_argument("--graph", required=True)
    args = parser.parse_args()
    try:
        problems, n_built, n_doc = check(args.doc, args.graph)
    except (OSError, ParseError) as e:
        print(f"architecture.target_graph: {e}")
        return 2
    if problems:
        print(f"architecture.target_graph: {args.doc} and the CMake target graph disagree "
              f"({len(problems)} differences):")
        for p in problems:
            print("  " + p)
        return 1
    print(f"architecture.target_graph: {n_doc} documented targets match CMake's {n_built}, "
          f"and every dependency points to a lower layer")
    return 0


if __name__ == "__main__":
    sys.exit(main())
