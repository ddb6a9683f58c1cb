"""One chunk of native samples of a pass of multi-view path tracing in Dr.Jit: the estimator
of docs/multiview-path-tracing.md §2–§7 as `--method mvpt` renders it with its defaults
(every valid view shares; balance weights W_k = G_k / Σ_valid G_j, n = 1; one shared light
sample and one bounce from the mixture of the sharing views' lobes; the suffix traced once).

A chunk is a wavefront of native samples; its sharing a wavefront of (sample, view) pairs.
Every random number of a native sample comes from its own PCG32 stream, seeded by (seed,
view, pixel, pass), so a chunked pass equals an unchunked one."""
from __future__ import annotations

import numpy as np

from . import cameras


def power_heuristic(dr, a, b):
    """MIS power heuristic a² / (a² + b²) (0 where a is 0)."""
    a2, b2 = dr.square(a), dr.square(b)
    return dr.select(a2 > 0, a2 / (a2 + b2), 0.0)


def chunk_samples(ctx, start: int, end: int, pass_index: int):
    """Views, pixels and random streams of the native samples [start, end) of a pass (indices
    over every view's sample window, view after view)."""
    mi, views = ctx.mi, ctx.views
    g = np.arange(start, end, dtype=np.int64)
    view = np.searchsorted(views.sample_offsets, g, side="right") - 1
    local = g - views.sample_offsets[view]
    ww = views.window[1][view, 0]
    px = (views.window[0][view, 0] + local % ww).astype(np.float32)
    py = (views.window[0][view, 1] + local // ww).astype(np.float32)
    v = mi.UInt32(view.astype(np.uint32))
    a = mi.sample_tea_32(mi.UInt32(local.astype(np.uint32)), ctx.dr.opaque(mi.UInt32, pass_index))
    b = mi.sample_tea_32(v, ctx.dr.opaque(mi.UInt32, ctx.seed))
    rng = mi.PCG32(len(g))
    rng.seed(mi.UInt64(a[0]) | (mi.UInt64(a[1]) << 32), mi.UInt64(b[0]) | (mi.UInt64(b[1]) << 32))  # (no lane offset)
    return v, mi.Float(px), mi.Float(py), rng


def render_chunk(ctx, start: int, end: int, pass_index: int, film) -> None:
    """Trace, share and splat the native samples [start, end) of pass `pass_index` into `film`."""
    mi, dr, scene = ctx.mi, ctx.dr, ctx.scene
    view, px, py, rng = chunk_samples(ctx, start, end, pass_index)
    c = ctx.views.at(view, dr)
    xl = mi.Point2f(px + rng.next_float32(), py + rng.next_float32())
    lens = mi.warp.square_to_uniform_disk_concentric(mi.Point2f(rng.next_float32(), rng.next_float32()))
    ray = cameras.generate_ray(c, xl, lens, mi, dr)
    si = scene.ray_intersect(ray)
    hit = si.is_valid()
    # Emission seen directly and the environment on a miss: the native view's only (§7).
    emitted = mi.Color3f(0.0) if ctx.hide_emitters else si.emitter(scene).eval(si)
    film.splat(view, xl, emitted, dr.select(hit, 0.0, 1.0), mi.Bool(True))
    if ctx.max_depth == 1:
        return
    smooth = hit & mi.has_flag(si.bsdf(ray).flags(), mi.BSDFFlags.Smooth)
    p = Pairs(ctx, view, xl, lens, c, si, hit, smooth & ctx.share)
    ctx.shared_vertices += dr.sum(mi.Float(hit))
    ctx.contributions += dr.sum(mi.Float(p.sharing))
    nee = shared_light_sample(ctx, p, si, rng)
    factor, suffix_ray, prev = shared_bounce(ctx, p, si, rng)
    suffix = trace_suffix(ctx, suffix_ray, prev, rng)
    radiance = nee + factor * dr.gather(mi.Color3f, suffix, p.lane)
    film.splat(p.view, p.film, radiance * p.weight, p.weight, p.valid)


class Pairs:
    """The (sample, view) pairs of a chunk: the prefix shift of each first hit y to every view
    with its validity tests (§3: orientation, image, visibility; static scene: time always
    valid), and the balance weights W_k = G_k / Σ_valid G_j (§5 with n = 1). The native view's
    pair is always valid; a sample whose y cannot be shared keeps only that one, with W = 1."""

    def __init__(self, ctx, view, xl, lens, c_l, si, hit, shareable):
        mi, dr, views, scene = ctx.mi, ctx.dr, ctx.views, ctx.scene
        count = views.count
        pair = dr.arange(mi.UInt32, dr.width(view) * count)
        self.lane, self.view = pair // count, pair % count
        native_view = dr.gather(mi.UInt32, view, self.lane)
        self.native = self.view == native_view
        self.si = dr.gather(mi.SurfaceInteraction3f, si, self.lane)
        y, n = self.si.p, self.si.n
        xi = dr.gather(mi.Point2f, lens, self.lane)
        cl = {k: dr.gather(mi.Float, v, self.lane) for k, v in c_l.items()}
        u_l = cameras.lens_point(cl, xi, mi)
        _, _, g_l, _, _ = cameras.shift(cl, y, n, xi, mi, dr)
        film, u, g, visible, in_depth = cameras.shift(views.at(self.view, dr), y, n, xi, mi, dr)
        share = dr.gather(mi.Bool, shareable, self.lane) & (g_l > 0)
        same_side = dr.sign(dr.dot(n, u - y)) == dr.sign(dr.dot(n, u_l - y))
        inside = ((film.x >= dr.gather(mi.Float, views.win_x0, self.view))
                  & (film.x < dr.gather(mi.Float, views.win_x1, self.view))
                  & (film.y >= dr.gather(mi.Float, views.win_y0, self.view))
                  & (film.y < dr.gather(mi.Float, views.win_y1, self.view)))
        cand = share & ~self.native & in_depth & same_side & inside & (g > 0)
        to_u = dr.normalize(u - y)
        shadow = self.si.spawn_ray(to_u)
        shadow.maxt = visible * (1.0 - 1e-4)
        cand &= ~scene.ray_test(shadow, cand)
        self.valid = dr.gather(mi.Bool, hit, self.lane) & (self.native | cand)
        # Each view looks along u_k -> y; the native view keeps its own film position.
        self.si.wi = dr.select(self.native, self.si.wi, self.si.to_local(to_u))
        self.film = dr.select(self.native, dr.gather(mi.Point2f, xl, self.lane), film)
        # Sums over a sample's views in view order (its pairs are contiguous): deterministic,
        # unlike atomic adds, whose order depends on how the launch is split.
        gamma = dr.block_sum(dr.select(self.valid & share, dr.select(self.native, g_l, g), 0.0), count)
        self.sharing = dr.block_sum(mi.UInt32(self.valid), count)  # |S|
        g_self = dr.select(self.native, g_l, g)
        self.weight = dr.select(share, g_self / dr.gather(mi.Float, gamma, self.lane), 1.0)
        self.weight = dr.select(self.valid, self.weight, 0.0)
        self.bsdf = self.si.bsdf()
        self.count = count

    def mixture_pdf(self, ctx, wo_world):
        """p_mix(ω) = (1/|S|) Σ_{c∈S} p_c(ω | ω_c) per sample (§7), and each pair's f_k cos."""
        mi, dr = ctx.mi, ctx.dr
        wo = self.si.to_local(dr.gather(mi.Vector3f, wo_world, self.lane))
        value, pdf = self.bsdf.eval_pdf(mi.BSDFContext(), self.si, wo, self.valid)
        total = dr.block_sum(dr.select(self.valid, pdf, 0.0), self.count)
        return total / dr.maximum(mi.Float(self.sharing), 1.0), value


def shared_light_sample(ctx, p: Pairs, si, rng):
    """Next-event estimation, one light sample shared by every view of S, each view's
    contribution f_k cos L_e / p_L weighted against the mixture's density (§7)."""
    mi, dr = ctx.mi, ctx.dr
    ds, em_weight = ctx.scene.sample_emitter_direction(si, mi.Point2f(rng.next_float32(), rng.next_float32()),
                                                       True, si.is_valid())
    p_mix, f = p.mixture_pdf(ctx, ds.d)
    mis = dr.select(ds.delta, 1.0, power_heuristic(dr, ds.pdf, p_mix))
    return f * dr.gather(mi.Color3f, em_weight * mis, p.lane)


def shared_bounce(ctx, p: Pairs, si, rng):
    """The bounce (§7): pick c ∈ S uniformly, sample ω from c's lobe; each view k gets
    f_k cos / p_mix(ω), or, where the sampled component is a delta lobe, c alone gets its
    weight times |S|. Returns each pair's factor, the suffix's ray and (y, p_mix, delta)."""
    mi, dr = ctx.mi, ctx.dr
    lanes = dr.width(si.p)
    u_pick = rng.next_float32()
    size = mi.Float(p.sharing)
    rank = dr.minimum(mi.UInt32(dr.floor(u_pick * size)), dr.maximum(p.sharing, 1) - 1)
    # The rank-th valid pair of each sample (pairs are in view order within a sample).
    order = dr.prefix_sum(mi.UInt32(p.valid))
    first = dr.gather(mi.UInt32, order, dr.arange(mi.UInt32, lanes) * p.count)
    chosen = p.valid & ((order - dr.gather(mi.UInt32, first, p.lane)) == dr.gather(mi.UInt32, rank, p.lane))
    pick = dr.zeros(mi.UInt32, lanes)
    dr.scatter(pick, dr.arange(mi.UInt32, dr.width(p.lane)), p.lane, chosen)
    si_c = dr.gather(mi.SurfaceInteraction3f, p.si, pick)
    bsdf_c = si_c.bsdf()
    active = si.is_valid() & (p.sharing > 0)
    bs, bs_weight = bsdf_c.sample(mi.BSDFContext(), si_c, rng.next_float32(),
                                  mi.Point2f(rng.next_float32(), rng.next_float32()), active)
    wo = si_c.to_world(bs.wo)
    delta = mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)
    active &= dr.any(bs_weight != 0.0)
    p_mix, f = p.mixture_pdf(ctx, wo)
    smooth_factor = f / dr.gather(mi.Float, p_mix, p.lane)
    delta_factor = dr.select(chosen, dr.gather(mi.Color3f, bs_weight * size, p.lane), 0.0)
    lane_delta = dr.gather(mi.Bool, delta, p.lane)
    factor = dr.select(lane_delta, delta_factor, dr.select(dr.gather(mi.Float, p_mix, p.lane) > 0, smooth_factor, 0.0))
    factor = dr.select(p.valid & dr.gather(mi.Bool, active, p.lane), factor, 0.0)
    ray = si.spawn_ray(wo)
    return factor, ray, (si, dr.select(delta, bs.pdf, p_mix), delta, active, bs.eta)


def trace_suffix(ctx, ray, prev, rng):
    """The path tracer from the bounce's ray on (Mitsuba 3's path semantics: NEE with the
    power heuristic, MIS at emitters hit against the previous vertex's density, Russian
    roulette from rr_depth), one kernel launch per vertex. The first vertex's density is the
    mixture's (§7). Returns the radiance per sample (throughput from the suffix's start)."""
    mi, dr, scene = ctx.mi, ctx.dr, ctx.scene
    prev_si, prev_pdf, prev_delta, active, eta = prev
    L = mi.Color3f(0.0)
    beta = mi.Color3f(1.0)
    depth = 1
    ctx_b = mi.BSDFContext()
    while True:
        si = scene.ray_intersect(ray, active)
        ds = mi.DirectionSample3f(scene, si, prev_si)
        em_pdf = scene.pdf_emitter_direction(prev_si, ds, active & ~prev_delta)
        mis = dr.select(prev_delta, 1.0, power_heuristic(dr, prev_pdf, em_pdf))
        L += dr.select(active, beta * mis * ds.emitter.eval(si, active), 0.0)
        active &= si.is_valid() & ((ctx.max_depth < 0) | (depth + 1 < ctx.max_depth))
        if not dr.any(active):
            break
        bsdf = si.bsdf(ray)
        active_em = active & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
        ds, em_weight = scene.sample_emitter_direction(si, mi.Point2f(rng.next_float32(), rng.next_float32()),
                                                       True, active_em)
        value, pdf = bsdf.eval_pdf(ctx_b, si, si.to_local(ds.d), active_em)
        mis_em = dr.select(ds.delta, 1.0, power_heuristic(dr, ds.pdf, pdf))
        L += dr.select(active_em, beta * mis_em * value * em_weight, 0.0)
        bs, weight = bsdf.sample(ctx_b, si, rng.next_float32(), mi.Point2f(rng.next_float32(), rng.next_float32()),
                                 active)
        ray = si.spawn_ray(si.to_world(bs.wo))
        beta *= weight
        eta *= bs.eta
        prev_si, prev_pdf = si, bs.pdf
        prev_delta = mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)
        depth += 1
        u_rr = rng.next_float32()
        if depth >= ctx.rr_depth:
            q = dr.minimum(dr.max(beta) * dr.square(eta), 0.95)
            survive = u_rr < q
            beta = dr.select(survive, beta / q, 0.0)
            active &= survive
        active &= dr.max(beta) != 0.0
        dr.eval(L, beta, active, ray, prev_si, prev_pdf, prev_delta, eta, rng)
    return L
