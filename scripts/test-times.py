#!/usr/bin/env python3
"""Seconds per test binary from `cargo test` logs, side by side (issue 49's check that a
change does not slow the test command).

Usage: scripts/test-times.py BEFORE.log [AFTER.log]

Each binary is named by its crate and source (`ember_cli tests/cli.rs`, `ember_core
src/lib.rs`, doc-tests as `doc ember_core`); its time is the `finished in` of its test
result (run time only: the binaries are built before). A binary that moved between crates
keeps its source name, so it is matched by that when its crate differs. Prints one row
per binary and the totals.
"""
import re
import sys


def times(path):
    out, current = {}, None
    for line in open(path, encoding="utf-8", errors="replace"):
        m = re.search(r"Running (\S+) \(target/\S+/deps/([A-Za-z0-9_]+?)-[0-9a-f]+\)", line)
        if m:
            source, binary = m.group(1), m.group(2)
            current = f"{binary} {source}"
            continue
        m = re.search(r"Running unittests (\S+) \(target/\S+/deps/([A-Za-z0-9_]+?)-[0-9a-f]+\)", line)
        if m:
            current = f"{m.group(2)} {m.group(1)}"
            continue
        m = re.match(r"\s*Doc-tests (\S+)", line)
        if m:
            current = f"doc {m.group(1)}"
            continue
        m = re.search(r"test result: \w+\..*finished in ([0-9.]+)s", line)
        if m and current:
            out[current] = out.get(current, 0.0) + float(m.group(1))
            current = None
    return out


def main():
    logs = [times(p) for p in sys.argv[1:]]
    if not logs:
        sys.exit(__doc__)
    names = sorted(set().union(*logs))
    by_source = [{k.split(" ", 1)[-1]: v for k, v in log.items()} for log in logs]
    print("binary".ljust(60) + "".join(f"{p[-24:]:>26}" for p in sys.argv[1:]))
    shown = set()
    for n in names:
        src = n.split(" ", 1)[-1]
        row = []
        for log, src_map in zip(logs, by_source):
            v = log.get(n, src_map.get(src) if src.startswith("tests/") else None)
            row.append(f"{v:26.2f}" if v is not None else f"{'-':>26}")
        key = (src if src.startswith("tests/") else n)
        if key in shown:
            continue
        shown.add(key)
        print(n[:60].ljust(60) + "".join(row))
    print("total".ljust(60) + "".join(f"{sum(log.values()):26.2f}" for log in logs))


if __name__ == "__main__":
    main()
