"""The tables printed after a render: one row per view, then the totals, and the statistics
of multi-view path tracing."""
from __future__ import annotations

import sys


def table(rows: list, header: list, align: str) -> str:
    """Plain-text table; `align` has one of '<' or '>' per column."""
    cells = [header] + [[str(c) for c in r] for r in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(header))]
    lines = ["  ".join(f"{c:{a}{w}}" for c, a, w in zip(r, align, widths)).rstrip() for r in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines) + "\n"


def si(x: float) -> str:
    for unit, scale in (("G", 1e9), ("M", 1e6), ("k", 1e3)):
        if abs(x) >= scale:
            return f"{x / scale:.2f} {unit}"
    return f"{x:.0f}"


def print_summary(result, stream=None) -> None:
    """The table printed after a render: one row per view, then the totals."""
    stream = stream if stream is not None else sys.stdout
    s = result.stats
    rows = []
    for vid, v in s["views"].items():
        m = v["mean"]
        rows.append([vid, f"{v['width']}x{v['height']}", f"{v['spp']:.1f}", f"{v['samples']:,}",
                     f"{m[0]:.4f}", f"{m[1]:.4f}", f"{m[2]:.4f}", f"{v['nonfinite_samples']:,}"])
    stream.write(table(rows, ["view", "size", "spp", "samples", "mean R", "mean G", "mean B", "non-finite"],
                        "<>>>>>>>"))
    state = "cancelled after" if s.get("cancelled") else "done in"
    if s.get("backend"):  # (Dr.Jit on Mitsuba counts no rays)
        stream.write(f"{state} {s['passes']} passes, {s['wall_time']:.2f} s on Mitsuba's {s['variant']}, method "
                     f"{s['method']}; samples: {s['samples']:,} ({si(s['samples_per_second'])}/s)"
                     + (f", mean |S| {s['multiview']['mean_sharing']:.2f}" if s["method"] == "mvpt" else "") + "\n")
        return
    r = s["rays"]
    stream.write(f"{state} {s['passes']} passes, {s['wall_time']:.2f} s (longest pass {s['max_pass_seconds']:.3f} s), "
                 f"{s['threads']} threads, integrator '{s['integrator']}', method {s.get('method', 'pt')}\n")
    stream.write(f"samples: {s['samples']:,} ({si(s['samples_per_second'])}/s)   "
                 f"rays: {r['total']:,} ({si(s['rays_per_second'])}/s; camera {r['camera']:,}, "
                 f"intersect {r['intersect']:,}, shadow {r['shadow']:,})\n")
    if s.get("method") == "mvpt":
        print_multiview_summary(s, stream)
    for note in s.get("notes", []):
        stream.write(f"note: {note}\n")
    if s.get("nonfinite_samples"):
        f = s.get("first_nonfinite") or {}
        stream.write(f"warning: {s['nonfinite_samples']:,} non-finite samples were dropped (first: view "
                     f"{f.get('view_id')}, pixel ({f.get('x')}, {f.get('y')}), sample {f.get('sample')})\n")


_TESTS = ("time", "orientation", "image", "bsdf", "visibility", "selection")


def print_multiview_summary(s: dict, stream) -> None:
    """Per-view statistics of multi-view path tracing (design doc §9): native samples,
    contributions received, mean sharing set size |S|, rays per native sample, and the share
    of shifts rejected by each validity test."""
    rows = []
    for vid, v in s["views"].items():
        m = v["multiview"]
        tried = max(1, m["shifts_tried"])
        rows.append([vid, f"{m['native_samples']:,}", f"{m['contributions']:,}", f"{m['mean_sharing']:.2f}",
                     f"{m['rays_per_native_sample']:.1f}"] +
                    [f"{100.0 * m['rejected'][t] / tried:.1f}%" for t in _TESTS])
    stream.write(f"multi-view path tracing ({s['estimator']}): rejected shifts by test, in % of those tried\n")
    stream.write(table(rows, ["view", "native", "received", "|S|", "rays/native"] + list(_TESTS), "<>>>>>>>>>>"))
