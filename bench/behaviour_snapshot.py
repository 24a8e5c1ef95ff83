"""A snapshot of what the compiler does, to prove a refactoring changed no behaviour (issue 33).

    python bench/behaviour_snapshot.py take OUT.json [--mutants 600] [--jobs 2]
    python bench/behaviour_snapshot.py compare BEFORE.json AFTER.json

`take` compiles, under each dialect preset and without one:
- every `.st` file of the repository (programs/, tests/fixtures/, tests/golden/, bench/workloads/,
  the thesis's programs) and every ST program held in a string by a test module (its triple-quoted
  constants that contain a POU), each alone;
- `--mutants` fuzz mutants of the example programs (st.testing.fuzz.mutant, seed 33);
and records, per unit and preset: every diagnostic (code, severity, file, line, column, message,
hint) and, when it compiles, the generated Python of each file (`--emit python`). `compare`
prints every unit whose record differs, and a count; it exits 1 if any does.
"""

from __future__ import annotations

import argparse
import ast
import concurrent.futures
import json
import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PRESETS = (None, "openplc", "iec", "codesys", "twincat")


def units(mutants: int) -> list[tuple[str, str]]:
    """(name, text) of everything compiled."""
    out: list[tuple[str, str]] = []
    for folder in ("programs", "tests/fixtures", "tests/golden", "bench/workloads"):
        for p in sorted((ROOT / folder).rglob("*.st")):
            out.append((str(p.relative_to(ROOT)), p.read_text(errors="replace")))
    for p in sorted((ROOT / "tests").glob("test_*.py")):
        try:
            tree = ast.parse(p.read_text())
        except SyntaxError:
            continue
        k = 0
        for node in ast.walk(tree):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and "\n" in node.value:
                text = node.value
                upper = text.upper()
                if any(w in upper for w in ("END_PROGRAM", "END_FUNCTION", "END_TYPE", "END_CONFIGURATION")):
                    out.append((f"{p.relative_to(ROOT)}#{k}", text))
                    k += 1
    if mutants:
        from st.testing.fuzz import mutant

        for i in range(mutants):
            name, text = mutant(33, i)[:2]
            out.append((f"mutant-{i}:{name}", text))
    return out


def record(unit: tuple[str, str]) -> tuple[str, dict]:
    from st.api import compile_text

    name, text = unit
    rec: dict = {}
    for preset in PRESETS:
        key = preset or "default"
        try:
            compiled = compile_text(
                text, "unit.st", dialect=preset, use_cache=False, raise_on_error=False, emit_python=True
            )
        except Exception as e:  # noqa: BLE001 - recorded: a refactoring must not change this either
            rec[key] = {"exception": f"{type(e).__name__}: {e}"[:300]}
            continue
        diags = [
            [str(d.code), str(d.severity), d.span.file, d.span.line, d.span.col, d.message, d.hint or ""]
            for d in compiled.diagnostics
        ]
        python = compiled.python_source if not any(d[1].lower().endswith("error") for d in diags) else None
        rec[key] = {"diagnostics": diags, "python": python}
    return name, rec


def take(out: str, mutants: int, jobs: int) -> None:
    todo = units(mutants)
    result: dict = {}
    with concurrent.futures.ProcessPoolExecutor(jobs) as pool:
        for name, rec in pool.map(record, todo, chunksize=8):
            result[name] = rec
    Path(out).write_text(json.dumps(result, sort_keys=True))
    print(f"{len(result)} units x {len(PRESETS)} presets -> {out}")


def compare(before: str, after: str) -> int:
    a, b = json.loads(Path(before).read_text()), json.loads(Path(after).read_text())
    differ = 0
    for name in sorted(set(a) | set(b)):
        if a.get(name) != b.get(name):
            differ += 1
            if differ <= 40:
                ra, rb = a.get(name) or {}, b.get(name) or {}
                for preset in sorted(set(ra) | set(rb)):
                    if ra.get(preset) != rb.get(preset):
                        x, y = ra.get(preset) or {}, rb.get(preset) or {}
                        what = "diagnostics" if x.get("diagnostics") != y.get("diagnostics") else "generated code"
                        print(f"{name} [{preset}]: {what} differ")
                        if what == "diagnostics":
                            print(f"   before: {x.get('diagnostics') or x.get('exception')}"[:600])
                            print(f"   after:  {y.get('diagnostics') or y.get('exception')}"[:600])
    print(f"{len(set(a) | set(b))} units compared, {differ} differ")
    return 1 if differ else 0


def main() -> None:
    sys.setrecursionlimit(10000)
    ap = argparse.ArgumentParser()
    sub = ap.add_subparsers(dest="cmd", required=True)
    t = sub.add_parser("take")
    t.add_argument("out")
    t.add_argument("--mutants", type=int, default=600)
    t.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    c = sub.add_parser("compare")
    c.add_argument("before")
    c.add_argument("after")
    args = ap.parse_args()
    if args.cmd == "take":
        take(args.out, args.mutants, args.jobs)
    else:
        sys.exit(compare(args.before, args.after))


if __name__ == "__main__":
    main()
