"""A snapshot of what the compiler does, to prove a refactoring changed no behaviour (issue 33).

    python bench/behaviour_snapshot.py take OUT.json [--mutants 600] [--jobs 2]
    python bench/behaviour_snapshot.py compare BEFORE.json AFTER.json [--ignore-codes E013=E053,...] [--allow-new]

`take` compiles, under each dialect preset and without one:
- every `.st` file of the repository (programs/, tests/fixtures/, tests/golden/, bench/workloads/,
  the thesis's programs) and every ST program held in a string by a test module (its triple-quoted
  constants that contain a POU), each alone;
- `--mutants` fuzz mutants of the example programs (st.testing.fuzz.mutant, seed 33);
and records, per unit and preset: every diagnostic (code, severity, file, line, column, message,
hint) and, when it compiles, the generated Python of each file (`--emit python`). `compare`
prints every unit whose record differs, and a count; it exits 1 if any does. `--ignore-codes
OLD=NEW,...` lets a diagnostic whose code was deliberately moved from OLD to NEW count as the same
one when everything else about it (severity, file, line, column, message, hint, its place in the
list) is, and counts those moves; `--allow-new` lists the units only AFTER has (files added since
BEFORE) without counting them as differences.
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


def compare(before: str, after: str, ignore_codes: str = "", allow_new: bool = False) -> int:
    a, b = json.loads(Path(before).read_text()), json.loads(Path(after).read_text())
    moves = _code_moves(ignore_codes)
    moved: dict[tuple[str, str], int] = {}
    differ = 0
    new = sorted(set(b) - set(a)) if allow_new else []
    for name in sorted((set(a) | set(b)) - set(new)):
        if _same_unit(a.get(name), b.get(name), moves, moved):
            continue
        differ += 1
        if differ <= 40:
            ra, rb = a.get(name) or {}, b.get(name) or {}
            for preset in sorted(set(ra) | set(rb)):
                if not _same_unit({"": ra.get(preset)}, {"": rb.get(preset)}, moves, {}):
                    x, y = ra.get(preset) or {}, rb.get(preset) or {}
                    what = "diagnostics" if x.get("diagnostics") != y.get("diagnostics") else "generated code"
                    print(f"{name} [{preset}]: {what} differ")
                    if what == "diagnostics":
                        print(f"   before: {x.get('diagnostics') or x.get('exception')}"[:600])
                        print(f"   after:  {y.get('diagnostics') or y.get('exception')}"[:600])
    for (old, to), n in sorted(moved.items()):
        print(f"{n} diagnostics moved from {old} to {to} (all else identical)")
    if new:
        print(f"{len(new)} units only in {after} (new files), not compared: {', '.join(new)}")
    print(f"{len(set(a) | set(b)) - len(new)} units compared, {differ} differ")
    return 1 if differ else 0


def _code_moves(spec: str) -> set[tuple[str, str]]:
    """`E013=E053,E043=E061` → {("E013", "E053"), ("E043", "E061")}."""
    moves = set()
    for pair in filter(None, (p.strip() for p in spec.split(","))):
        old, _, new = pair.partition("=")
        if not (old and new):
            raise SystemExit(f"--ignore-codes: '{pair}' is not OLD=NEW")
        moves.add((old.strip().upper(), new.strip().upper()))
    return moves


def _same_unit(x, y, moves: set, moved: dict) -> bool:
    """The records of one unit (preset → record) are equal but for the allowed code moves, which
    are counted in `moved` (only when the whole unit is equal so)."""
    if x == y:
        return True
    if not moves or not isinstance(x, dict) or not isinstance(y, dict) or set(x) != set(y):
        return False
    found: dict[tuple[str, str], int] = {}
    for preset in x:
        rx, ry = x[preset] or {}, y[preset] or {}
        if set(rx) != set(ry) or any(rx[k] != ry[k] for k in rx if k != "diagnostics"):
            return False
        dx, dy = rx.get("diagnostics") or [], ry.get("diagnostics") or []
        if len(dx) != len(dy):
            return False
        for p, q in zip(dx, dy):
            if p == q:
                continue
            if p[1:] != q[1:] or (p[0], q[0]) not in moves:
                return False
            found[(p[0], q[0])] = found.get((p[0], q[0]), 0) + 1
    for k, n in found.items():
        moved[k] = moved.get(k, 0) + n
    return True


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
    c.add_argument("--ignore-codes", default="", help="OLD=NEW,...: codes deliberately moved (all else must be equal)")
    c.add_argument("--allow-new", action="store_true", help="units only AFTER has are listed, not counted")
    args = ap.parse_args()
    if args.cmd == "take":
        take(args.out, args.mutants, args.jobs)
    else:
        sys.exit(compare(args.before, args.after, args.ignore_codes, args.allow_new))


if __name__ == "__main__":
    main()
