"""HTML report of an equal-time benchmark: one self-contained index.html.

Every image (crops, error maps, plots) is embedded as a data: URI, so the page opens in a
browser from anywhere, with nothing beside it; the report directory also keeps the
runs' EXRs/JSON and bench.json with every number. The page reports its own loading in
#load-status (images decoded, script and console errors) for the headless-browser test."""
from __future__ import annotations

import base64
import html
import io
import json
from pathlib import Path

import numpy as np

from . import metrics
from .bench import BenchResult, shell
from .images import as_rgb, srgb8
from .output import _json_clean, write_json_atomic

CROP = 96           # crop side in pixels (the whole view when it is smaller)
MAX_DETAIL_VIEWS = 16

_STYLE = """
body { font: 14px/1.4 system-ui, sans-serif; margin: 1.5em auto; max-width: 1200px; color: #222; }
h1 { font-size: 1.5em; } h2 { border-bottom: 1px solid #ccc; margin-top: 2em; }
table { border-collapse: collapse; margin: .5em 0; }
td, th { border: 1px solid #ddd; padding: 3px 8px; text-align: right; vertical-align: top; }
th { background: #f4f4f4; } td.l, th.l { text-align: left; }
p.warning { background: #fff3cd; border: 1px solid #e0c060; padding: 6px 10px; }
figure { margin: 0 8px 8px 0; text-align: center; }
div.grid { display: grid; }
figcaption { font-size: 12px; color: #444; }
img.px { image-rendering: pixelated; width: 192px; }
img.plot { max-width: 100%; }
pre { background: #f6f6f6; padding: 8px; overflow-x: auto; white-space: pre-wrap; }
#load-status { color: #666; font-size: 12px; }
"""

# Records script errors, failed resources and console.error calls, then, once the page has
# loaded, counts the images that did not decode; the result goes into #load-status.
_STATUS_SCRIPT = """
(function () {
  var errors = [];
  window.addEventListener('error', function (e) {
    errors.push(e.message || ('failed to load ' + ((e.target && (e.target.src || e.target.href)) || 'a resource')));
  }, true);
  var consoleError = console.error;
  console.error = function () { errors.push(Array.prototype.join.call(arguments, ' ')); consoleError.apply(console, arguments); };
  window.addEventListener('load', function () {
    var imgs = document.images, broken = 0;
    for (var i = 0; i < imgs.length; i++) if (!imgs[i].complete || imgs[i].naturalWidth === 0) broken++;
    var s = document.getElementById('load-status');
    s.setAttribute('data-state', 'loaded');
    s.setAttribute('data-images', imgs.length);
    s.setAttribute('data-broken', broken);
    s.setAttribute('data-errors', errors.length);
    s.textContent = imgs.length + ' images, ' + broken + ' not shown, ' + errors.length + ' errors' +
                    (errors.length ? ': ' + errors.join('; ') : '');
  });
})();
"""


def _e(x) -> str:
    return html.escape(str(x), quote=True)


def _png_uri(rgb8: np.ndarray) -> str:
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(rgb8)).save(buf, format="PNG")
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def _figure_uri(fig) -> str:
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100, bbox_inches="tight")
    plt.close(fig)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")  # no display: render to PNG only
    import matplotlib.pyplot as plt
    return plt


def colorize(values: np.ndarray, vmax: float = 1.0, cmap: str = "magma") -> np.ndarray:
    """(H, W) values in [0, vmax] -> uint8 RGB through a matplotlib color map."""
    import matplotlib

    v = np.clip(np.nan_to_num(np.asarray(values, dtype=np.float64)) / vmax, 0.0, 1.0)
    rgba = matplotlib.colormaps[cmap](v)
    return np.round(rgba[..., :3] * 255).astype(np.uint8)


def best_crop(error: np.ndarray, size: int) -> tuple:
    """(y, x, h, w) of the size x size window with the largest summed `error` (H, W) (summed-area table)."""
    h, w = error.shape
    ch, cw = min(size, h), min(size, w)
    s = np.zeros((h + 1, w + 1))
    s[1:, 1:] = np.cumsum(np.cumsum(np.nan_to_num(error), axis=0), axis=1)
    win = s[ch:, cw:] - s[:-ch, cw:] - s[ch:, :-cw] + s[:-ch, :-cw]
    y, x = np.unravel_index(int(np.argmax(win)), win.shape)
    return int(y), int(x), ch, cw


def _num(x, fmt="{:.4g}") -> str:
    return "n/a" if x is None or not np.isfinite(x) else fmt.format(x)


def _subtracts_noise(result: BenchResult) -> bool:
    """Whether the plots show errors with the reference's noise subtracted: when it is known
    and leaves some error positive (else the raw errors, and the warnings say why)."""
    return bool(result.reference_noise) and any(
        v > 0 for r in result.methods.values() for v in r.corrected.values())


def _positive(x: float) -> float:
    """x, or NaN (not plotted on a log scale) where the reference's noise exceeds the error."""
    return x if x > 0 else float("nan")


def _relmse_plot(result: BenchResult) -> str:
    plt = _pyplot()
    methods = list(result.methods)
    views = list(next(iter(result.methods.values())).errors.views)
    fig, ax = plt.subplots(figsize=(max(5.0, 0.6 * len(views) * max(1, len(methods)) + 2), 3.2))
    width = 0.8 / max(1, len(methods))
    x = np.arange(len(views))
    corrected = _subtracts_noise(result)
    for i, m in enumerate(methods):
        r = result.methods[m]
        vals = [_positive(r.corrected[v]) if corrected else r.errors.views[v].relmse for v in views]
        ax.bar(x + (i - (len(methods) - 1) / 2) * width, vals, width, label=m)
    ax.set_xticks(x, views, rotation=45 if len(views) > 6 else 0, ha="right" if len(views) > 6 else "center")
    ax.set_yscale("log")
    ax.set_ylabel("relMSE" + (" - reference noise" if corrected else ""))
    ax.set_title(f"relMSE per view at {result.config.time:g} s" +
                 (" (the reference's noise subtracted)" if corrected else ""))
    ax.legend()
    ax.grid(axis="y", which="both", alpha=0.3)
    return _figure_uri(fig)


def _convergence_plot(result: BenchResult) -> str:
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(5.5, 3.6))
    corrected = _subtracts_noise(result)
    for m, r in result.methods.items():
        t = [p["seconds"] for p in r.curve]
        e = [_positive(p["relmse_corrected"]) if corrected else p["relmse"] for p in r.curve]
        ax.loglog(t, e, "o-", label=m)
    ax.set_xlabel("render time (s)")
    ax.set_ylabel("relMSE (all views)" + (" - reference noise" if corrected else ""))
    ax.set_title("Convergence")
    ax.grid(which="both", alpha=0.3)
    ax.legend()
    return _figure_uri(fig)


def _summary_table(result: BenchResult) -> str:
    rows = []
    for m, r in result.methods.items():
        s = r.run.stats or {}
        views = s.get("views", {})
        spp = np.mean([v["spp"] for v in views.values()]) if views else float("nan")
        o = r.errors.overall
        rows.append(f"<tr><td class=l>{_e(m)}</td><td>{_num(s.get('wall_time'), '{:.2f}')}</td>"
                    f"<td>{_e(s.get('passes', ''))}</td><td>{_num(spp, '{:.1f}')}</td>"
                    f"<td>{_num(s.get('samples_per_second'), '{:.3g}')}</td><td>{_num(o.rmse)}</td>"
                    f"<td>{_num(o.relmse)}</td><td>{_num(r.corrected.get('overall'))}</td>"
                    f"<td>{_num(r.display.get('relmse'))}</td><td>{_num(r.display.get('relmse_corrected'))}</td>"
                    f"<td>{_num(o.flip)}</td></tr>")
    noise = result.reference_noise.get("overall")
    rows.append(f"<tr><td class=l>reference's own noise</td><td></td><td></td><td></td><td></td><td></td>"
                f"<td>{_num(noise)}</td><td></td><td>{_num(result.display_noise)}</td><td></td><td></td></tr>")
    return ("<table><tr><th class=l>method</th><th>time (s)</th><th>passes</th><th>spp (mean)</th>"
            "<th>samples/s</th><th>RMSE</th><th>relMSE</th><th>relMSE &minus; reference noise</th>"
            "<th>relMSE as a display shows the views</th><th>the same &minus; reference noise</th><th>FLIP</th></tr>"
            + "".join(rows) + "</table>"
            + "<p>A display shows each view blended with its neighbours along its row (1/4, 1/2, 1/4, as a "
              "lenticular panel's crosstalk does): paths shared between views make their noise alike, so what a "
              "viewer sees gains less from sharing than each view alone.</p>")


def _warnings(result: BenchResult) -> str:
    return "".join(f"<p class=warning><b>Warning:</b> {_e(w)}</p>" for w in result.warnings)


def _outline(rgb8: np.ndarray, y: int, x: int, h: int, w: int) -> np.ndarray:
    """A copy of `rgb8` with a 1-pixel red rectangle around the crop."""
    out = rgb8.copy()
    red = np.array([255, 0, 0], np.uint8)
    out[y, x:x + w] = out[y + h - 1, x:x + w] = red
    out[y:y + h, x] = out[y:y + h, x + w - 1] = red
    return out


def _figure(uri: str, alt: str, caption: str) -> str:
    return f'<figure><img class=px src="{uri}" alt="{_e(alt)}"><figcaption>{_e(caption)}</figcaption></figure>'


def _view_section(result: BenchResult, vid: str) -> str:
    ref = as_rgb(result.reference.images[vid] if vid in result.reference.images
                 else next(iter(result.reference.images.values())))
    tests = {m: as_rgb(r.run.images[vid]) for m, r in result.methods.items()}
    maps = {m: metrics.flip_map(x, ref)[0] for m, x in tests.items()}
    y, x, h, w = best_crop(sum(maps.values()), CROP)
    crop = (slice(y, y + h), slice(x, x + w))
    whole = h == ref.shape[0] and w == ref.shape[1]
    # Row 1: the reference and each method on the crop; row 2: where the crop lies, and each
    # method's FLIP error map on the crop (magma: black = no visible difference, 1 = yellow).
    top = [_figure(_png_uri(srgb8(ref[crop])), f"reference {vid}", "reference")]
    bottom = [_figure(_png_uri(_outline(srgb8(ref), y, x, h, w)), f"crop of {vid}", "crop in the full view")
              if not whole else "<figure></figure>"]
    for m, img in tests.items():
        e = result.methods[m].errors.views[vid]
        top.append(_figure(_png_uri(srgb8(img[crop])), f"{m} {vid}",
                           f"{m}: relMSE {_num(e.relmse)}, FLIP {_num(e.flip)}"))
        bottom.append(_figure(_png_uri(colorize(maps[m][crop])), f"FLIP error {m} {vid}", f"FLIP error, {m}"))
    where = ("whole view" if whole else
             f"crop x {x}..{x + w - 1}, y {y}..{y + h - 1}, where the FLIP error is largest")
    return (f"<h3>{_e(vid)}</h3><p>{ref.shape[1]}x{ref.shape[0]} pixels; {_e(where)}.</p>"
            f'<div class=grid style="grid-template-columns: repeat({len(top)}, max-content)">'
            f"{''.join(top)}{''.join(bottom)}</div>")


def _stats_section(result: BenchResult) -> str:
    parts = []
    for m, r in result.methods.items():
        s = r.run.stats or {}
        rays = s.get("rays", {})
        parts.append(f"<tr><td class=l>{_e(m)}</td><td>{_e(s.get('samples', ''))}</td>"
                     f"<td>{_e(rays.get('total', ''))}</td><td>{_num(s.get('rays_per_second'), '{:.3g}')}</td>"
                     f"<td>{_e(s.get('threads', ''))}</td><td>{_e(s.get('nonfinite_samples', ''))}</td>"
                     f"<td class=l>{_e(r.directory)}</td></tr>")
    details = "".join(f"<details><summary>{_e(m)}: full statistics</summary><pre>"
                      f"{_e(json.dumps(_json_clean(r.run.stats), indent=2, sort_keys=True))}</pre></details>"
                      for m, r in result.methods.items())
    curve = "".join(f"<tr><td class=l>{_e(m)}</td><td>{_num(p['budget'], '{:.3g}')}</td>"
                    f"<td>{_num(p['seconds'], '{:.3f}')}</td><td>{_e(p['samples'])}</td><td>{_num(p['relmse'])}</td></tr>"
                    for m, r in result.methods.items() for p in r.curve)
    return ("<table><tr><th class=l>method</th><th>samples</th><th>rays</th><th>rays/s</th><th>threads</th>"
            "<th>non-finite</th><th class=l>images</th></tr>" + "".join(parts) + "</table>" + details +
            "<h3>Convergence points</h3><table><tr><th class=l>method</th><th>budget (s)</th><th>time (s)</th>"
            "<th>samples</th><th>relMSE</th></tr>" + curve + "</table>")


def render_html(result: BenchResult) -> str:
    """The report page as a string."""
    cfg = result.config
    env = result.environment
    views = list(next(iter(result.methods.values())).errors.views)
    shown = views[:MAX_DETAIL_VIEWS]
    more = (f"<p>{len(views) - len(shown)} more views are in bench.json and the run directories.</p>"
            if len(views) > len(shown) else "")
    commands = [shell(cfg.command())]
    if result.reference_command and result.reference_command[0] != "(given)":
        commands.append("# the reference alone:\n" + shell(result.reference_command))
    commands += [f"# {m} alone:\n" + shell(r.command) for m, r in result.methods.items()]
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<title>mvpt equal-time: {_e(Path(cfg.scene).name)}, {cfg.time:g} s</title>
<style>{_STYLE}</style>
<script>{_STATUS_SCRIPT}</script>
</head><body>
<h1>Equal-time comparison: {_e(Path(cfg.scene).name)}, {cfg.time:g} s per method</h1>
<p>Methods {_e(', '.join(cfg.methods))} on {len(views)} view(s); reference: {_e(result.reference.source)}.
mvpt {_e(env.get('mvpt'))}, Python {_e(env.get('python'))}, {_e(env.get('platform'))}, {_e(env.get('cpus'))} CPUs,
{_e(env.get('date'))}.</p>
<p>RMSE = sqrt(mean (x-r)&sup2;); relMSE = mean (x-r)&sup2;/(r&sup2;+{metrics.RELMSE_EPS:g}) over pixels and channels;
FLIP = mean HDR-FLIP error (flip-evaluator). "All views" pools every pixel. The reference has noise of its own,
which adds mean Var(r)/(r&sup2;+{metrics.RELMSE_EPS:g}) to every relMSE (Var(r): the variance of its pixel means);
{"it is subtracted in the last relMSE column" + (" and in the plots" if _subtracts_noise(result) else
 " (not in the plots: it exceeds every error)") if result.reference_noise else
 "its variance is unknown, so it is not subtracted"}.</p>
{_warnings(result)}
<h2>Summary</h2>
{_summary_table(result)}
<h2>relMSE per view</h2>
<img class=plot src="{_relmse_plot(result)}" alt="relMSE per view">
<h2>Convergence (relMSE against time)</h2>
<img class=plot src="{_convergence_plot(result)}" alt="convergence curves">
<h2>Views: crops and FLIP error maps</h2>
{''.join(_view_section(result, v) for v in shown)}{more}
<h2>Run statistics</h2>
{_stats_section(result)}
<h2>Reproduce</h2>
<pre>{_e(chr(10).join(commands))}</pre>
<footer><p id="load-status" data-state="pending">loading&hellip;</p></footer>
</body></html>
"""


def write_report(result: BenchResult, out_dir=None) -> str:
    """Write <out>/index.html (self-contained) and <out>/bench.json; returns the HTML path."""
    out = Path(out_dir if out_dir is not None else result.config.output)
    out.mkdir(parents=True, exist_ok=True)
    page = render_html(result)
    path = out / "index.html"
    tmp = out / ".index.html.tmp"
    tmp.write_text(page, encoding="utf-8")
    tmp.replace(path)
    write_json_atomic(out / "bench.json", result.as_json())
    return str(path)
