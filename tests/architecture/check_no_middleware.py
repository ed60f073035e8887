#!/usr/bin/env python3
"""Checks that no header of the layers below communication reaches the middleware.

Every header (*.hpp, *.h) under the given include folders is preprocessed on its own by the
compiler (`-E -H`: the include tree as the compiler resolves it, macros and conditional
includes included), with the include folders of every compile command of the build
(compile_commands.json). A header fails when any file in its include tree, directly or
through other headers, is Fast DDS (fastdds/, fastrtps/, fastcdr/), a generated IDL type
(handshare/idl/) or the DDS layer (handshare/dds/); the check prints the include chain.

usage: check_no_middleware.py --compile-commands BUILD/compile_commands.json --compiler CXX
                              --root SOURCE_DIR DIR [DIR ...]
Exit status 0 when every header is clean, 1 when one is not (or cannot be preprocessed).
"""
import argparse
import concurrent.futures
import json
import os
import re
import shlex
import subprocess
import sys

# A path component sequence that marks a file as middleware (checked on the resolved path).
FORBIDDEN = [
    ("Fast DDS", re.compile(r"/(fastdds|fastrtps|fastcdr)/")),
    ("generated IDL types", re.compile(r"/handshare/idl/")),
    ("the DDS layer", re.compile(r"/handshare/dds/")),
]


def include_flags(compile_commands):
    """Every -I / -isystem / -iquote folder of the build's compile commands, in first-seen order."""
    with open(compile_commands) as f:
        entries = json.load(f)
    seen, flags = set(), []
    for e in entries:
        args = e.get("arguments") or shlex.split(e["command"])
        directory = e.get("directory", ".")
        i = 0
        while i < len(args):
            a, opt, path = args[i], None, None
            if a in ("-I", "-isystem", "-iquote", "-idirafter") and i + 1 < len(args):
                opt, path, i = a, args[i + 1], i + 1
            else:
                for o in ("-isystem", "-iquote", "-idirafter", "-I"):
                    if a.startswith(o) and len(a) > len(o):
                        opt, path = o, a[len(o):]
                        break
            if opt is not None:
                path = os.path.normpath(os.path.join(directory, path))
                if (opt, path) not in seen:
                    seen.add((opt, path))
                    flags += [opt, path]
            i += 1
    return flags


def forbidden_kind(path):
    normal = "/" + os.path.realpath(path).lstrip("/")
    for what, pattern in FORBIDDEN:
        if pattern.search(normal):
            return what
    return None


def include_tree(compiler, flags, header):
    """[(depth, path)] of every file the header includes, in the order the compiler reads them
    (up to a fatal error), and the compiler's errors."""
    cmd = [compiler, "-std=c++20", "-x", "c++", "-E", "-H", "-o", os.devnull, *flags, header]
    r = subprocess.run(cmd, capture_output=True, text=True)
    tree, errors = [], []
    for line in r.stderr.splitlines():
        m = re.match(r"^(\.+) (.*)$", line)
        if m:
            tree.append((len(m.group(1)), m.group(2)))
        elif re.search(r"\berror: ", line):
            errors.append(line)
    if r.returncode == 0:
        return tree, []  # warnings (such as "#pragma once in main file") are no concern here
    return tree, errors or [f"{' '.join(cmd)} exited with {r.returncode}"]


def offending_chains(header, tree):
    """Each first middleware file of a branch, with the chain of includes that reached it."""
    chains, stack = [], []
    skip_below = None  # inside a middleware file: its own includes are not reported again
    for depth, path in tree:
        if skip_below is not None and depth > skip_below:
            continue
        skip_below = None
        del stack[depth - 1:]
        stack.append(path)
        what = forbidden_kind(path)
        if what:
            chains.append((what, list(stack)))
            skip_below = depth
    return chains


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--compile-commands", required=True)
    parser.add_argument("--compiler", required=True)
    parser.add_argument("--root", required=True, help="the source tree (paths are printed relative to it)")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("dirs", nargs="+", help="include folders whose headers must stay clean")
    args = parser.parse_args()

    root = os.path.realpath(args.root)
    rel = lambda p: os.path.relpath(os.path.realpath(p), root) if os.path.realpath(p).startswith(root + "/") else p
    try:
        flags = include_flags(args.compile_commands)
    except (OSError, ValueError, KeyError) as e:
        print(f"architecture.no_middleware_in_core: cannot read {args.compile_commands}: {e}")
        return 1
    headers = []
    for d in args.dirs:
        d = os.path.join(root, d)
        if not os.path.isdir(d):
            print(f"architecture.no_middleware_in_core: {rel(d)} is not a folder")
            return 1
        flags += ["-I", d]  # the checked folders are include folders themselves
        for base, _, files in os.walk(d):
            headers += [os.path.join(base, f) for f in files if f.endswith((".hpp", ".h", ".hh"))]
    headers.sort()
    if not headers:
        print("architecture.no_middleware_in_core: no headers found")
        return 1

    failures = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        results = pool.map(lambda h: (h, include_tree(args.compiler, flags, h)), headers)
        for header, (tree, errors) in results:
            if errors:
                failures.append(f"{rel(header)}: cannot be preprocessed on its own:\n      " + "\n      ".join(errors))
            for what, chain in offending_chains(header, tree):
                failures.append(f"{rel(header)} reaches {what}: " + " -> ".join([rel(header)] + [rel(p) for p in chain]))

    if failures:
        print(f"architecture.no_middleware_in_core: {len(failures)} problems "
              f"in {len(headers)} headers of {', '.join(args.dirs)}:")
        for f in failures:
            print("  " + f)
        return 1
    print(f"architecture.no_middleware_in_core: {len(headers)} headers checked; none reaches Fast DDS, "
          f"the generated IDL types or handshare/dds")
    return 0


if __name__ == "__main__":
    sys.exit(main())
