"""Small test scenes (rectangles and cubes, two sensors, box filter) shared by
the emitter render tests, and the statistics that compare two renderers."""
from __future__ import annotations

import numpy as np
from scipy import stats

SIZE = 32


def sensors(views, size=SIZE, fov=45, spp=16):
    out = []
    for i, (origin, target, up) in enumerate(views):
        out.append(f"""<sensor type="perspective" id="v{i}"><float name="fov" value="{fov}"/>
  <transform name="to_world"><lookat origin="{origin}" target="{target}" up="{up}"/></transform>
  <sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>
  <film type="hdrfilm"><integer name="width" value="{size}"/><integer name="height" value="{size}"/>
  <rfilter type="box"/></film></sensor>""")
    return "\n".join(out)


ROOM_VIEWS = [("0, -4.5, 2.2", "0, 0, 0.6", "0, 0, 1"), ("3, -3, 1.6", "0, 0.2, 0.5", "0, 0, 1")]

ROOM = """
<bsdf type="diffuse" id="white"><rgb name="reflectance" value="0.7"/></bsdf>
<shape type="rectangle"><transform name="to_world"><scale value="3"/></transform><ref id="white"/></shape>
<shape type="rectangle"><transform name="to_world"><scale value="3"/><rotate x="1" angle="90"/><translate y="2" z="1"/></transform>
  <bsdf type="diffuse"><rgb name="reflectance" value="0.3, 0.5, 0.7"/></bsdf></shape>
<shape type="cube"><transform name="to_world"><scale value="0.45"/><rotate z="1" angle="25"/><translate x="0.3" y="0.2" z="0.45"/></transform>
  <bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.3, 0.2"/></bsdf></shape>
"""


def scene_xml(body, views=ROOM_VIEWS, max_depth=4, spp=16, size=SIZE, fov=45):
    return f"""<scene version="3.0.0">
<integrator type="path"><integer name="max_depth" value="{max_depth}"/></integrator>
{body}
{sensors(views, size=size, fov=fov, spp=spp)}
</scene>"""


def render_mitsuba(xml, n_views, spp, seeds):
    """Per view: (mean image, variance of that mean) over independent seeds."""
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    scene = mi.load_string(xml)
    out = []
    for v in range(n_views):
        imgs = np.stack([np.array(mi.render(scene, sensor=v, spp=spp, seed=s))[..., :3] for s in range(seeds)])
        out.append((imgs.mean(0), imgs.var(0, ddof=1) / seeds))
    return out


def block_z(mean_a, var_a, mean_b, var_b, block=4):
    """z-scores of block means per channel, from per-pixel variances of pixel means
    (pixels are independent, so a block's variance is the sum over its pixels)."""
    def blocks(x):
        h, w, c = x.shape
        return x.reshape(h // block, block, w // block, block, c).sum(axis=(1, 3))

    a, b = blocks(mean_a) / block**2, blocks(mean_b) / block**2
    var = (blocks(np.maximum(var_a, 0)) + blocks(np.maximum(var_b, 0))) / block**4
    # Noise-free blocks (e.g. a directly seen constant background) still differ by
    # float round-off between renderers: allow for single-precision resolution.
    var += (1e-6 * np.maximum(np.abs(a), np.abs(b))) ** 2
    return (a - b) / np.sqrt(var + 1e-30)


def compare(ours, ref, n_tests, alpha=0.01):
    """Mean within 1% and Sidak-corrected two-sided block z-tests. `ours`/`ref`:
    lists of (mean image, variance of mean) per view. Returns a list of failures."""
    failures = []
    zs = [block_z(a[0], a[1], b[0], b[1]) for a, b in zip(ours, ref)]
    n_blocks = sum(z.size for z in zs) * n_tests
    p_min = 1 - (1 - alpha) ** (1 / n_blocks)
    z_crit = stats.norm.isf(p_min / 2)
    for i, ((ma, _), (mb, _), z) in enumerate(zip(ours, ref, zs)):
        rel = abs(ma.mean() - mb.mean()) / mb.mean()
        if rel > 0.01:
            failures.append(f"view {i}: mean {ma.mean():.5f} vs {mb.mean():.5f} ({100 * rel:.2f}%)")
        if np.abs(z).max() > z_crit:
            k = np.unravel_index(np.abs(z).argmax(), z.shape)
            failures.append(f"view {i}: block {k} z = {z[k]:.2f} > {z_crit:.2f}")
    return failures
