"""What distributing a render over Ray costs: per task and per merged range, and the bytes
that cross the network, measured on local Ray nodes; and the efficiency those costs imply for
real nodes (docs/distributed.md).

    python bench/bench_distributed.py                  # 1, 2 and 3 local nodes of one CPU
    python bench/bench_distributed.py --quick          # smaller film, fewer passes

The scene is the 9-view glossy Cornell box rendered by multi-view path tracing. The
reference is one process rendering all passes with one thread (`single`). Each Ray run
starts a cluster of N local nodes (ray.cluster_utils.Cluster, one CPU each) and renders the
same passes as N x --tasks-per-node ranges. On a machine with fewer cores than nodes the
nodes share cores (oversubscribed): their wall times then measure contention, and what the
script reports as the cost of distribution comes from the tasks' own clocks instead:

- task overhead: the driver's wall time minus the merges, times the workers, minus the
  tasks' render seconds, per task (scheduling, the scene's unpacking and loading, the state
  written, sent and read back);
- merge: the driver's seconds per range folded into the merged state (serial);
- bytes: the scene's pack (once per worker process) and each range's state, also per
  view-pixel.

Runs are interleaved over --repeat rounds and medians reported. The model for N real nodes of
C cores with tasks of T seconds each: the render parallelises, the task overhead adds o per
task, the merges m per task run serially in the driver, so efficiency(N) = T / (T + o + N m)
once every node has work.
"""
from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "cornell-glossy-9.xml"


def single(res: int, passes: int) -> float:
    import mvpt
    scene = mvpt.load_file(SCENE, res=res)
    t = time.monotonic()
    mvpt.render(scene, seed=1, method="mvpt", threads=1, passes=(0, passes))
    return time.monotonic() - t


def distributed_run(nodes: int, res: int, passes: int, tasks_per_node: int) -> dict:
    import ray
    from ray.cluster_utils import Cluster
    from mvpt import distributed
    cluster = Cluster(initialize_head=True, head_node_args={"num_cpus": 1})
    for _ in range(nodes - 1):
        cluster.add_node(num_cpus=1)
    ray.init(address=cluster.address, include_dashboard=False, log_to_driver=False)
    try:
        r = distributed.render(SCENE, spp=passes, seed=1, method="mvpt", defines={"res": res}, workers=nodes,
                               task_cpus=1, tasks_per_worker=tasks_per_node)
    finally:
        ray.shutdown()
        cluster.shutdown()
    d = dict(r.stats["distributed"])
    d["view_pixels"] = sum(v["width"] * v["height"] for v in r.stats["views"].values())
    return d


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--nodes", default="1,2,3")
    ap.add_argument("--res", type=int, default=64)
    ap.add_argument("--passes", type=int, default=96)
    ap.add_argument("--tasks-per-node", type=int, default=4)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    if args.quick:
        args.res, args.passes, args.repeat = 32, 48, 1
    nodes = [int(n) for n in args.nodes.split(",")]
    singles, runs = [], {n: [] for n in nodes}
    for _ in range(args.repeat):
        singles.append(single(args.res, args.passes))
        for n in nodes:
            runs[n].append(distributed_run(n, args.res, args.passes, args.tasks_per_node))
    t1 = statistics.median(singles)
    print(f"9-view glossy Cornell box, {args.res}^2, {args.passes} passes, mvpt; medians of {args.repeat}")
    print(f"single process, 1 thread: {t1:.2f} s")
    print(f"{'nodes':>5} {'tasks':>5} {'wall s':>7} {'render s/task':>13} {'overhead s/task':>15} "
          f"{'merge s/range':>13} {'state MB/task':>13} {'B/view-pixel':>12} {'pack kB':>7}")
    model = None
    for n in nodes:
        rows = runs[n]
        med = lambda f: statistics.median(f(r) for r in rows)
        tasks = rows[0]["tasks"]
        render = med(lambda r: sum(r["task_seconds"]) / r["tasks"])
        overhead = med(lambda r: max(0.0, ((r["wall_seconds"] - r["merge_seconds"]) * r["workers"]
                                           - sum(r["task_seconds"])) / r["tasks"]))
        merge = med(lambda r: r["merge_seconds"] / r["tasks"])
        state = med(lambda r: r["state_bytes_returned"] / r["tasks"])
        print(f"{n:>5} {tasks:>5} {med(lambda r: r['wall_seconds']):>7.2f} {render:>13.3f} {overhead:>15.3f} "
              f"{merge:>13.4f} {state / 1e6:>13.2f} {state / rows[0]['view_pixels']:>12.1f} "
              f"{rows[0]['scene_pack_bytes'] / 1e3:>7.1f}")
        if n == 1:
            model = (overhead, merge)
    if model:
        o, m = model
        print(f"model (one node's costs): efficiency(N) = T / (T + {o:.3f} + N x {m:.4f}) for tasks of T seconds")
        for T in (10.0, 60.0, 600.0):
            eff = [T / (T + o + N * m) for N in (1, 4, 16, 64)]
            print(f"  T = {T:>5.0f} s: " + "  ".join(f"N={N}: {e:.3f}" for N, e in zip((1, 4, 16, 64), eff)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
