"""The holder check's material step (`machinesim.cutting.holder.holder_in_material`) on
helical bores whose holder enters the part and on a pocket whose holder does not: the walk
in program order (the package's, ``new``) against the algorithm before it (``old``, kept
here: for each candidate sweep, the stock in its holder's room less the earlier sweeps one
at a time until nothing is left), in the same run.

Each case is cut with ``machinesim.cut`` on grooving_4axis into a block whose top is z = 0.
A bore, in a ``block:6x6x15`` centred on it: G02 half turns of radius 0.4 mm about the
origin, 0.25 mm down each, to the depth, then a full circle there (its chords do not line
up with the half turns', so the wall keeps slivers of some 1e-15 m^3 in the rooms over
them), the arcs split within the tool's path chord (100 nm):

- ``deep``: 12.8 mm deep with ``flat:1.35`` (its 10 mm body's top under the stock's top in
  the bore): refused until the holder was judged within one chord (docs/cutting.md), cut
  now (0 of 994 candidates found, the check 13.5 s of CPU);
- ``short``: 1.5 mm deep with ``flat:1.35:h=1``: refused so too, cut now;
- ``pocket``, not refused (the levels below the body find the pocket the levels above
  opened): ``flat:1.0`` (10 mm body) down 11 mm in 0.5 mm levels, each a plunge at the
  corner and five passes 4 mm along X, 0.5 mm apart in Y, joined by steps in Y (265
  sweeps with the rapids up), in a ``block:10x8x15`` reaching 3 mm past its start; the
  whole cut timed.

Printed per case and method: the median over ``--repeat`` runs of the check's own time
(and its process's CPU time, the fairer figure on a shared machine) and of the whole call
(until the refusal, where there is one), with the sweeps, the candidates (the box step's)
and the sweeps found; both methods must find the same. Each run is its own process; a
method whose run passes ``--timeout`` seconds is stopped and quoted so.

    .venv/bin/python benchmarks/holder_check.py [--repeat 3] [--cases deep short pocket]
        [--methods new old] [--timeout 3600]
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time

import numpy as np

#: case: depth (mm), tool, stock
CASES = {"deep": (12.8, "flat:1.35", "block:6x6x15@-3,-3,0"),
         "short": (1.5, "flat:1.35:h=1", "block:6x6x15@-3,-3,0"),
         "pocket": (11.0, "flat:1.0", "block:10x8x15@-3,-3,0")}


def bore(depth_mm: float, radius_mm: float = 0.4, pitch_mm: float = 0.25) -> str:
    """The bore's program text (mm)."""
    lines = ["G21 G90 G94", f"G00 X{radius_mm} Y0. Z0.1", "G01 Z0. F100."]
    z, k, x = 0.0, 0, radius_mm
    while z > -depth_mm + 1e-9:
        z = max(z - pitch_mm, -depth_mm)
        x = -radius_mm if k % 2 == 0 else radius_mm
        lines.append(f"G02 X{x:.4f} Y0. Z{z:.4f} I{x:.4f} J0.")
        k += 1
    lines += [f"G02 X{x:.4f} Y0. I{-x:.4f} J0.", "G00 Z1."]
    return "\n".join(lines) + "\n"


def pocket(depth_mm: float, level_mm: float = 0.5) -> str:
    """The pocket's program text (mm): zigzag levels down to ``depth_mm``."""
    lines = ["G21 G90 G94", "G00 X0. Y0. Z1."]
    for k in range(1, int(round(depth_mm / level_mm)) + 1):
        lines.append(f"G01 Z{-k * level_mm:.4f} F100.")
        for n in range(5):
            if n:
                lines.append(f"G01 Y{0.5 * n:.4f}")
            lines.append(f"G01 X{4.0 if n % 2 == 0 else 0.0:.4f}")
        lines += ["G00 Z1.", "G00 X0. Y0."]
    return "\n".join(lines) + "\n"


def old_holder_in_material(sweeps, candidates, solid, reach, keep=None,
                           tolerance=0.0) -> list[int]:
    """`holder_in_material` before the walk: each candidate's material less the earlier
    sweeps one at a time (those sharing most of its box first) until none is left."""
    from machinesim.cutting.holder import HOLDER_MATERIAL_M3, holder_room

    inside = {}
    for i in (int(i) for i in candidates):
        met = solid ^ holder_room(sweeps, i, reach, tolerance)
        if met.volume() > HOLDER_MATERIAL_M3:
            inside[i] = met
    if not inside or keep is None:
        return list(inside)
    boxes = np.array([met.bounding_box() for met in inside.values()]).reshape(-1, 6)

    def into_a_room(low, high):
        meets = ((low[:, None, :] <= boxes[None, :, 3:])
                 & (high[:, None, :] >= boxes[None, :, :3])).all(axis=2).any(axis=1)
        return keep(low, high) & meets

    hulls, lower, upper, *_, owners = sweeps.hulls(into_a_room)
    owners = np.asarray(owners, dtype=np.int64)
    found = []
    for (i, met), box in zip(inside.items(), boxes, strict=True):
        earlier = np.flatnonzero((owners < i) & (lower <= box[3:]).all(axis=1)
                                 & (upper >= box[:3]).all(axis=1))
        shared = np.prod(np.clip(np.minimum(upper[earlier], box[3:])
                                 - np.maximum(lower[earlier], box[:3]), 0.0, None), axis=1)
        earlier = earlier[np.argsort(-shared, kind="stable")]
        left = met.volume()
        for j in earlier:
            if left <= HOLDER_MATERIAL_M3:
                break
            met = met - hulls[j]
            left = met.volume()
        if left > HOLDER_MATERIAL_M3:
            found.append(i)
    return found


def child(case: str, method: str) -> dict:
    """One run: the bore cut until its refusal, the check timed."""
    import machinesim.cutting.holder as holder
    from machinesim.cutting import cut
    from machinesim.exceptions import HolderContactError
    from machinesim.nc import parse_program
    from machinesim.tool_specs import tool_from_spec
    from machinesim.tools import path_chord_tolerance

    depth, tool, stock = CASES[case]
    check = holder.holder_in_material if method == "new" else old_holder_in_material
    seen: dict = {"check_s": 0.0, "check_cpu_s": 0.0, "sweeps": 0, "candidates": 0,
                  "found": []}  # as left when no sweep is a candidate

    def timed(sweeps, candidates, solid, reach, keep=None, tolerance=0.0):
        start, cpu = time.perf_counter(), time.process_time()
        found = check(sweeps, candidates, solid, reach, keep, tolerance)
        seen.update(check_s=time.perf_counter() - start,
                    check_cpu_s=time.process_time() - cpu, sweeps=sweeps.count,
                    candidates=len(candidates), found=[int(i) for i in found])
        return found

    holder.holder_in_material = timed
    text = pocket(depth) if case == "pocket" else bore(depth)
    program = parse_program(text, chord_tolerance=path_chord_tolerance(
        [tool_from_spec(tool)]))
    start = time.perf_counter()
    try:
        cut(program, "grooving_4axis", tool=tool, stock=stock)
        seen["refused"] = False
    except HolderContactError:
        seen["refused"] = True
    seen["call_s"] = time.perf_counter() - start
    return seen


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--cases", nargs="+", choices=sorted(CASES),
                        default=["short", "deep", "pocket"])
    parser.add_argument("--methods", nargs="+", choices=["new", "old"], default=["new", "old"])
    parser.add_argument("--timeout", type=float, default=3600.0)
    parser.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        print(json.dumps(child(*args.child)))
        return
    for case in args.cases:
        depth, tool, _ = CASES[case]
        results = {}
        for method in args.methods:
            runs = []
            for _ in range(args.repeat):
                command = [sys.executable, __file__, "--child", case, method]
                try:
                    out = subprocess.run(command, check=True, capture_output=True, text=True,
                                         timeout=args.timeout).stdout
                except subprocess.TimeoutExpired:
                    runs = None
                    break
                runs.append(json.loads(out.splitlines()[-1]))
            results[method] = runs
            if runs is None:
                print(f"{case} ({depth} mm, {tool}), {method}: stopped after "
                      f"{args.timeout:.0f} s", flush=True)
                continue
            first = runs[0]
            span = (f" (sweeps {first['found'][0]} .. {first['found'][-1]})"
                    if first["found"] else "")
            print(f"{case} ({depth} mm, {tool}), {method}, median of {len(runs)}: check "
                  f"{statistics.median(r['check_s'] for r in runs):.2f} s (CPU "
                  f"{statistics.median(r['check_cpu_s'] for r in runs):.2f} s), whole call"
                  f" {statistics.median(r['call_s'] for r in runs):.2f} s; "
                  f"{first['sweeps']} sweeps, {first['candidates']} candidates, "
                  f"{len(first['found'])} found{span}, refused: {first['refused']}", flush=True)
        done = [runs for runs in results.values() if runs]
        if len(done) > 1:
            same = all(r["found"] == done[0][0]["found"] for runs in done for r in runs)
            print(f"{case}: the methods find the same sweeps: {same}", flush=True)


if __name__ == "__main__":
    main()
