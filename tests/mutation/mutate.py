#!/usr/bin/env python3
"""Applies one-line mutations one at a time, rebuilds and runs the named test programs, and reports
which test killed each. The source file is always restored, also on Ctrl-C.

The test that killed a mutation last time (tests/mutation/killers.txt) runs first, alone: most mutations
die there in seconds, and only the others run their whole test programs. --record writes the killers
found back to that file."""
import argparse
import pathlib
import re
import signal
import subprocess
import sys
import time

SEP = " @@ "


def load(path):
    muts = []
    for n, line in enumerate(pathlib.Path(path).read_text().splitlines(), 1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        fields = [f.strip() for f in line.split(SEP)]
        if len(fields) != 6:
            sys.exit(f"{path}:{n}: expected 6 fields separated by '{SEP.strip()}', got {len(fields)}")
        mid, modules, file, before, after, what = fields
        muts.append(dict(id=mid, modules=[m.strip() for m in modules.split(",")], file=file,
                         before=before, after=after, what=what, line=n))
    ids = [m["id"] for m in muts]
    dup = {i for i in ids if ids.count(i) > 1}
    if dup:
        sys.exit(f"{path}: duplicate ids {sorted(dup)}")
    return muts


def failed_tests(output):
    names = re.findall(r"^\[  FAILED  \] ([\w/.]+)", output, re.M)
    return list(dict.fromkeys(n for n in names if "." in n))


def load_killers(path):
    killers = {}
    p = pathlib.Path(path)
    if p.exists():
        for line in p.read_text().splitlines():
            if line.strip() and not line.lstrip().startswith("#"):
                mid, test = line.split()
                killers[mid] = test
    return killers


def save_killers(path, killers):
    lines = ["# The test that last killed each mutation of mutations.txt (written by mutate.py --record);",
             "# run first, alone, before the whole test programs."]
    lines += [f"{mid} {test}" for mid, test in sorted(killers.items())]
    pathlib.Path(path).write_text("\n".join(lines) + "\n")


def run_tests(exe, args, timeout):
    """(killed, what, failed test names) for one run of a test program."""
    try:
        r = subprocess.run([str(exe), *args], capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return True, f"timeout ({timeout} s)", []
    if r.returncode == 0:
        return False, "", []
    names = failed_tests(r.stdout)
    shown = names or [f"exit code {r.returncode}"]
    return True, ", ".join(shown[:3]) + (" ..." if len(shown) > 3 else ""), names


def run_mutation(m, build, timeout, killer=None):
    src = pathlib.Path(m["file"])
    original = src.read_text()
    if original.count(m["before"]) != 1:
        return "bad entry", f"'before' found {original.count(m['before'])} times in {src}", 0.0
    t0 = time.monotonic()
    targets = [f"eds_test_{mod}" for mod in m["modules"]]
    try:
        src.write_text(original.replace(m["before"], m["after"], 1))
        b = subprocess.run(["cmake", "--build", build, "--target", *targets], capture_output=True, text=True)
        if b.returncode != 0:
            return "no compile", "", time.monotonic() - t0
        exes = [(mod, pathlib.Path(build) / "tests" / f"eds_test_{mod}") for mod in m["modules"]]
        # The last killer alone first; then the whole programs, each stopped at its first failure.
        passes = ([["--gtest_filter=" + killer]] if killer else []) + [["--gtest_fail_fast"]]
        for args in passes:
            for mod, exe in exes:
                killed, what, names = run_tests(exe, args, timeout)
                if killed:
                    m["killer"] = names[0] if names else None
                    return "killed", f"{mod}: {what}", time.monotonic() - t0
        return "survived", "", time.monotonic() - t0
    finally:
        src.write_text(original)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", required=True)
    ap.add_argument("--list", required=True)
    ap.add_argument("--timeout", type=int, default=900, help="seconds per test program")
    ap.add_argument("--killers", default="tests/mutation/killers.txt")
    ap.add_argument("--record", action="store_true", help="write the killers found to --killers")
    ap.add_argument("ids", nargs="*")
    a = ap.parse_args()
    # The source must be restored however the run ends: SIGTERM, and SIGINT even where a background
    # shell started it with SIGINT ignored, unwind through the `finally` blocks.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(1))
    muts = load(a.list)
    # A header mutation rebuilds every file that includes it: those go last.
    muts.sort(key=lambda m: m["file"].endswith((".hpp", ".h")))
    killers = load_killers(a.killers)
    if a.ids:
        unknown = set(a.ids) - {m["id"] for m in muts}
        if unknown:
            sys.exit(f"unknown mutation ids: {sorted(unknown)}")
        muts = [m for m in muts if m["id"] in a.ids]
    # Each mutation rebuilds only the test programs, so the programs the tests run (eds itself) must
    # first match the unmutated sources: a stale one fails the command-line tests whatever the mutation.
    subprocess.run(["cmake", "--build", a.build], capture_output=True)
    rows = []
    print("| mutation | file | what | result | killed by | s |\n|---|---|---|---|---|---|", flush=True)
    try:
        for m in muts:
            result, by, secs = run_mutation(m, a.build, a.timeout, killers.get(m["id"]))
            if a.record and m.get("killer"):
                killers[m["id"]] = m["killer"]
                save_killers(a.killers, killers)
            rows.append((m, result))
            print(f"| {m['id']} | {m['file']} | {m['what']} | {result} | {by} | {secs:.0f} |", flush=True)
    finally:  # leave the build matching the restored sources
        subprocess.run(["cmake", "--build", a.build], capture_output=True)
    valid = [r for r in rows if r[1] in ("killed", "survived")]
    killed = sum(r[1] == "killed" for r in valid)
    print(f"\nkilled {killed} of {len(valid)} ({100.0 * killed / max(1, len(valid)):.0f} %); "
          f"not compiled or bad entries: {len(rows) - len(valid)}")
    for m, res in rows:
        if res == "survived":
            print(f"survived: {m['id']} ({m['file']}: {m['what']})")


if __name__ == "__main__":
    main()
