#!/usr/bin/env python3
"""Applies one-line mutations one at a time, rebuilds and runs the named test programs, and reports
which test killed each. The source file is always restored, also on Ctrl-C."""
import argparse
import pathlib
import re
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


def run_mutation(m, build, timeout):
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
        for mod in m["modules"]:
            exe = pathlib.Path(build) / "tests" / f"eds_test_{mod}"
            try:
                # The first failing test is enough to kill a mutation; the rest would only cost time.
                r = subprocess.run([str(exe), "--gtest_fail_fast"], capture_output=True, text=True,
                                   timeout=timeout)
            except subprocess.TimeoutExpired:
                return "killed", f"{mod}: timeout ({timeout} s)", time.monotonic() - t0
            if r.returncode != 0:
                names = failed_tests(r.stdout) or [f"exit code {r.returncode}"]
                return "killed", f"{mod}: " + ", ".join(names[:3]) + (" ..." if len(names) > 3 else ""), \
                    time.monotonic() - t0
        return "survived", "", time.monotonic() - t0
    finally:
        src.write_text(original)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", required=True)
    ap.add_argument("--list", required=True)
    ap.add_argument("--timeout", type=int, default=900, help="seconds per test program")
    ap.add_argument("ids", nargs="*")
    a = ap.parse_args()
    muts = load(a.list)
    if a.ids:
        unknown = set(a.ids) - {m["id"] for m in muts}
        if unknown:
            sys.exit(f"unknown mutation ids: {sorted(unknown)}")
        muts = [m for m in muts if m["id"] in a.ids]
    rows = []
    print("| mutation | file | what | result | killed by | s |\n|---|---|---|---|---|---|", flush=True)
    try:
        for m in muts:
            result, by, secs = run_mutation(m, a.build, a.timeout)
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
