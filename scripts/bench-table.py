#!/usr/bin/env python3
"""The kernel table of the README from one run of sere-bench: each kernel's time, its floor (the
same memory traffic with no arithmetic, meeting at the same barriers) and its peer (a library or
the reference twin), at 1 and 2 threads, all read from one Google Benchmark JSON file, so every
ratio in a row compares numbers measured in the same process, minutes apart.

    sere-bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \\
               --benchmark_out=run.json --benchmark_filter="$(scripts/bench-table.py --filter)"
    scripts/bench-table.py run.json > kernels.md      (make bench-table does both)
    scripts/bench-table.py after.json --before before.json

Times are the medians over repetitions (the numbers to quote on a shared machine); a run without
repetitions gives each benchmark's single time. With --before, a second run of another build
(interleave the two on a noisy machine) adds the ratio of the two builds' times at 1 thread.
A benchmark missing from the file shows as "–"; a file that is not a benchmark JSON, or that has
none of the table's benchmarks, is an error naming the file."""
import argparse
import json
import re
import sys

# One row per kernel. ours/floor: a benchmark name with {t} for the thread count; peers: (label,
# name) pairs, {t} where the peer runs threads too; per: calls of the measured unit a benchmark
# iteration runs (a sweep of a 200-sweep call). why: where the kernel stands against its floor,
# as the profiles and floors of docs/DESIGN.md explain it.
ROWS = [
    dict(kernel="PBD sweep, maple (51102 constraints), µs a sweep",
         ours="BM_PBDColored/threads:{t}/sweeps:200/real_time",
         floor="BM_PBDFloor/threads:{t}/sweeps:200/real_time",
         peers=[("AoS reference", "BM_PBDReference")], per=200, peer_per=1,
         why="record loads and their latency; the √ and two divisions a constraint, in part hidden "
             "by measuring one block ahead"),
    dict(kernel="XPBD sweep, the same, as a drying frame runs it, µs a sweep",
         ours="BM_XPBDColored/threads:{t}/sweeps:200/real_time",
         floor="BM_XPBDFloor/threads:{t}/sweeps:200/real_time",
         peers=[], per=200,
         why="as PBD, with a third division and the multiplier's load and store"),
    dict(kernel="descent sweep (the frame's step), the same springs, µs a sweep",
         ours="BM_VBDStep/threads:{t}/sweeps:40/real_time",
         floor="BM_VBDFloor/threads:{t}/sweeps:40/real_time",
         peers=[("serial twin in double, a sweep and its two gradient passes", "BM_VBDReference")],
         per=40, peer_per=1,
         why="the divider and the arithmetic: a √ and a division a spring end (14.5 cycles a row of 16 "
             "on this EPYC's divider, which the floor does not use), about 22 operations a row for the "
             "sums and a 3 × 3 solve a particle, on the pipes the floor's gather shuffles on (the "
             "gradient alone without the divider: 1.33–1.35×); a frame needs fewer of these sweeps "
             "than of XPBD's"),
    dict(kernel="PCG to 1e-8, maple T system, Jacobi",
         ours="BM_PCG/system:0/threads:{t}/sgs:0/real_time",
         floor="BM_PCGFloor/system:0/threads:{t}/real_time",
         peers=[("Eigen CG", "BM_EigenCG/system:0/threads:{t}/real_time"),
                ("hypre BoomerAMG-PCG, solve only", "BM_HypreAMG/system:0/setup:0/real_time")],
         why="the SELL product's gathers and the vectors' streams: bandwidth"),
    dict(kernel="PCG to 1e-8, maple T system, multicolor SGS (the osmosis's choice)",
         ours="BM_PCG/system:0/threads:{t}/sgs:1/real_time",
         floor="BM_SGSFloor/system:0/threads:{t}/real_time",
         peers=[("Eigen CG", "BM_EigenCG/system:0/threads:{t}/real_time")],
         why="half Jacobi's iterations, each a backward and a forward sweep over every entry; the floor "
             "has the steps alone, the solve also its start, restart and two true residuals"),
    dict(kernel="PCG to 1e-8, plane tree V system (λ = 100), multigrid, levels refreshed",
         ours="BM_AMG/system:2/threads:{t}/refresh:1/real_time",
         floor="BM_AMGFloor/system:2/threads:{t}/real_time",
         peers=[("hypre BoomerAMG-PCG with setup", "BM_HypreAMG/system:2/setup:1/real_time"),
                ("Eigen CG", "BM_EigenCG/system:2/threads:{t}/real_time")],
         why="the V-cycle's gathers; its coarse levels run on one thread"),
    dict(kernel="collision search, dense (maple dried to the end), with the refit",
         ours="BM_collide_search/dense/{t}/real_time",
         floor="BM_collide_search_floor/dense/{t}/real_time",
         peers=[("Embree rtcPointQuery, search alone", "BM_embree_search/dense/{t}/real_time")],
         why="the tests' arithmetic (separating-plane bounds, the edge table) over chains of "
             "index-then-record loads in L2"),
    dict(kernel="collision pass served by the candidate list, dense, moved",
         ours="BM_collide_pass_listed/dense/{t}/1/real_time",
         floor="BM_collide_pass_listed_floor/dense/{t}/1/real_time",
         peers=[],
         why="the scale taken off the motion and the exact tests of the pairs it leaves"),
    dict(kernel="edge–triangle crossing count, dense",
         ours="BM_crossings_count/dense/{t}/real_time",
         floor=None,
         peers=[("brute-force twin (dried)", "BM_crossings_ref_count/dried")],
         why="the grid's walk and its build (one thread); a floor would repeat them"),
    dict(kernel="mass-spring step (seed 002), maple T layer",
         ours="BM_MassSpringStep/threads:{t}/real_time",
         floor="BM_MassSpringFloor/threads:{t}/real_time",
         peers=[("scalar reference", "BM_MassSpringReference")],
         why="each spring's √ and division in the force pass and every sweep"),
    dict(kernel="shrinkage (Eq. 11–12), 51102 springs",
         ours="BM_Shrink/threads:{t}/real_time",
         floor="BM_ShrinkFloor/threads:{t}/real_time",
         peers=[("libm pow", "BM_ShrinkLibm")],
         why="arithmetic: Eq. 12's power in double, an exp and a log a spring"),
    dict(kernel="Markov day (seed 002), 10⁶ leaves",
         ours="BM_MarkovAdvance/threads:{t}/real_time",
         floor="BM_MarkovFloor/threads:{t}/real_time",
         peers=[],
         why="compute: a counter-based random number and seven compares a leaf, in cache"),
    dict(kernel="skinning (seed 003), 100 leaves, 500 thousand vertices",
         ours="BM_skeleton_skin/{t}/real_time",
         floor="BM_skeleton_skin_floor/{t}/real_time",
         peers=[("Eigen affine transforms", "BM_skeleton_skin_eigen/{t}/real_time"),
                ("scalar reference", "BM_skeleton_skin_ref/real_time")],
         why="each run of vertices sharing a joint: the scan for its end (a lane width of joint "
             "indices in one compare) and its transform's loads; the floor streams the same 28 "
             "bytes a vertex"),
    dict(kernel="banding (seed 003), one leaf",
         ours="BM_skeleton_band_leaf/{t}/real_time",
         floor="BM_skeleton_band_leaf_floor/{t}/real_time",
         peers=[("brute-force reference", "BM_skeleton_band_leaf_ref/real_time")],
         why="each joint's distance and the branch on an improvement, in short ring loops"),
    dict(kernel="banding (seed 003), a plant of 100 leaves",
         ours="BM_skeleton_band_plant/{t}/real_time",
         floor="BM_skeleton_band_plant_floor/{t}/real_time",
         peers=[("Embree rtcPointQuery", "BM_skeleton_band_plant_embree/{t}/real_time"),
                ("brute-force reference", "BM_skeleton_band_plant_ref/real_time")],
         why="as the leaf, with more cells opened a query"),
    dict(kernel="posing (seed 003), 100 leaves, 4500 joints",
         ours="BM_skeleton_pose/{t}/real_time",
         floor="BM_skeleton_pose_floor/{t}/real_time",
         peers=[],
         why="compute and latency: each joint's rotation waits for its parent's"),
]
THREADS = (1, 2)
TO_US = {"ns": 1e-3, "us": 1.0, "ms": 1e3, "s": 1e6}


def names():
    """Every benchmark the table reads, at both thread counts."""
    out = set()
    for row in ROWS:
        for t in THREADS:
            out.update(n.format(t=t) for n in [row["ours"], row["floor"]] + [p for _, p in row["peers"]] if n)
    return sorted(out)


def filter_regex():
    """A --benchmark_filter that runs the table's benchmarks and no others."""
    return "^(" + "|".join(re.escape(n) for n in names()) + ")$"


def load(path):
    """{run name: µs a call}: the median aggregate where the run has repetitions, else the run."""
    try:
        with open(path, encoding="utf-8") as f:
            data = json.load(f)
        entries = data["benchmarks"]
    except (OSError, ValueError, KeyError, TypeError) as e:
        sys.exit(f"bench-table: {path}: not a Google Benchmark JSON file ({e})")
    times, medians = {}, {}
    for b in entries:
        if not isinstance(b, dict) or "real_time" not in b or b.get("error_occurred"):
            continue
        name = b.get("run_name", b.get("name"))
        us = b["real_time"] * TO_US.get(b.get("time_unit", "ns"), 1e-3)
        if b.get("run_type") == "aggregate":
            if b.get("aggregate_name") == "median":
                medians[name] = us
        else:
            times.setdefault(name, us)
    times.update(medians)
    if not any(n in times for n in names()):
        sys.exit(f"bench-table: {path}: none of the table's benchmarks (run sere-bench with "
                 f"--benchmark_filter=\"$(scripts/bench-table.py --filter)\")")
    return data.get("context", {}), times


def fmt_time(us):
    if us is None:
        return "–"
    if us >= 1e4:
        return f"{us / 1e3:.1f} ms"
    if us >= 1e3:
        return f"{us / 1e3:.2f} ms"
    return f"{us:.3g} µs"


def fmt_ratio(a, b):
    if a is None or b is None or b <= 0:
        return "–"
    r = a / b
    return f"{r:.2f}×" if r >= 0.1 else f"{r:.2g}×"


def cell(times, name, t, per):
    if name is None:
        return None
    us = times.get(name.format(t=t))
    return None if us is None else us / per


def peers_text(row, times):
    parts = []
    ours = {t: cell(times, row["ours"], t, row.get("per", 1)) for t in THREADS}
    for label, name in row["peers"]:
        per = row.get("peer_per", row.get("per", 1))
        ones = [(t, cell(times, name, t, per)) for t in (THREADS if "{t}" in name else (1,))]
        shown = [f"{fmt_time(us)} ({fmt_ratio(ours[t], us)} ours/peer{'' if len(ones) == 1 else f', {t} t'})"
                 for t, us in ones if us is not None]
        if shown:
            parts.append(f"{label}: " + "; ".join(shown))
    return "<br>".join(parts) if parts else "–"


def table(context, times, before=None):
    lines = []
    machine = ", ".join(str(context[k]) for k in ("cpu", "simd", "compiler") if k in context)
    load = context.get("load_avg")
    load = " / ".join(f"{v:.2f}" for v in load) if isinstance(load, list) else "?"
    head = [f"sere-bench {context.get('sere_version', '?')} (commit {context.get('commit', '?')}), "
            f"{machine}; run {context.get('date', '?')}, load {load}; "
            "medians over repetitions, ratios within this one run"]
    lines += head + [""]
    cols = ["kernel", "ours, 1 t", "floor, 1 t", "ours/floor, 1 t", "ours, 2 t", "floor, 2 t",
            "ours/floor, 2 t", "peer or twin", "where it stands against its floor"]
    if before is not None:
        cols.insert(7, "this build / before, 1 t")
    lines.append("| " + " | ".join(cols) + " |")
    lines.append("|" + "---|" * len(cols))
    for row in ROWS:
        per = row.get("per", 1)
        cells = [row["kernel"]]
        for t in THREADS:
            ours, floor = cell(times, row["ours"], t, per), cell(times, row["floor"], t, per)
            cells += [fmt_time(ours), fmt_time(floor), fmt_ratio(ours, floor)]
        if before is not None:
            cells.append(fmt_ratio(cell(times, row["ours"], 1, per), cell(before, row["ours"], 1, per)))
        cells += [peers_text(row, times), row["why"]]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("run", nargs="?", help="sere-bench --benchmark_out JSON")
    parser.add_argument("--before", help="a run of another build, for a build-against-build column")
    parser.add_argument("--filter", action="store_true", help="print the --benchmark_filter and stop")
    parser.add_argument("--check-names", metavar="LIST",
                        help="sere-bench --benchmark_list_tests output (- for stdin): fail if it lacks a "
                             "benchmark the table names")
    args = parser.parse_args()
    if args.filter:
        print(filter_regex())
        return
    if args.check_names:
        listed = set((sys.stdin if args.check_names == "-" else open(args.check_names)).read().split())
        missing = [n for n in names() if n not in listed]
        if missing:
            sys.exit("bench-table: sere-bench has no " + ", ".join(missing))
        print(f"bench-table: sere-bench has all {len(names())} benchmarks the table names")
        return
    if args.run is None:
        parser.error("a benchmark JSON file is needed (or --filter)")
    context, times = load(args.run)
    before = load(args.before)[1] if args.before else None
    sys.stdout.write(table(context, times, before))


if __name__ == "__main__":
    main()
