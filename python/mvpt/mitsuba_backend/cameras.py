"""The views' cameras as Dr.Jit arrays: camera rays and the prefix shift of
docs/multiview-path-tracing.md §2–§4, from the projection data of the C++ cameras
(render/camera_projection.h, `Scene.camera_model`), gathered per lane by view index."""
from __future__ import annotations

import numpy as np

# Field order of CameraProjection's flatten (render/camera_projection.h).
FIELDS = ("ox oy oz a0x a0y a0z a1x a1y a1z a2x a2y a2z r0x r0y r0z r1x r1y r1z r2x r2y r2z "
          "near far radius inv_fd tan_x tan_y ppo_x ppo_y width height f").split()


class ViewTable:
    """Every view's projection, sample window and pass-film offset, as arrays by view."""

    def __init__(self, mi, models: list):
        self.mi = mi
        data = np.array([m["projection"] for m in models], dtype=np.float32)
        self.fields = {name: mi.Float(data[:, i]) for i, name in enumerate(FIELDS)}
        crops = np.array([m["crop"] for m in models], dtype=np.int64)
        margins = np.array([m["margin"] for m in models], dtype=np.int64)
        self.crops, self.margins = crops, margins
        # Sample windows: the crop window grown by the filter's margin (SampleWindow).
        self.window = crops[:, :2] - margins[:, None], crops[:, 2:] + 2 * margins[:, None]
        sizes = self.window[1][:, 0] * self.window[1][:, 1]
        self.sample_offsets = np.concatenate([[0], np.cumsum(sizes)])
        pixels = crops[:, 2] * crops[:, 3]
        self.pixel_offsets = np.concatenate([[0], np.cumsum(pixels)])
        self.count = len(models)
        self.win_x0, self.win_y0 = mi.Float(self.window[0][:, 0]), mi.Float(self.window[0][:, 1])
        self.win_x1 = mi.Float(self.window[0][:, 0] + self.window[1][:, 0])
        self.win_y1 = mi.Float(self.window[0][:, 1] + self.window[1][:, 1])
        self.crop_x, self.crop_y = mi.Int32(crops[:, 0]), mi.Int32(crops[:, 1])
        self.crop_w, self.crop_h = mi.Int32(crops[:, 2]), mi.Int32(crops[:, 3])
        self.pixel_offset = mi.UInt32(self.pixel_offsets[:-1])

    def at(self, view, dr):
        """The projection fields of each lane's view (a dict of Floats)."""
        return {k: dr.gather(self.mi.Float, v, view) for k, v in self.fields.items()}


def _axes(c, mi):
    return (mi.Vector3f(c["a0x"], c["a0y"], c["a0z"]), mi.Vector3f(c["a1x"], c["a1y"], c["a1z"]),
            mi.Vector3f(c["a2x"], c["a2y"], c["a2z"]))


def lens_point(c, lens, mi):
    """u = o + r (xi.x e1 + xi.y e2) (§2)."""
    a0, a1, _ = _axes(c, mi)
    return mi.Point3f(c["ox"], c["oy"], c["oz"]) + a0 * (lens.x * c["radius"]) + a1 * (lens.y * c["radius"])


def generate_ray(c, film, lens, mi, dr):
    """The camera ray through film position `film` (pixels) from unit-disk point `lens` (§2):
    from the lens point towards the focus-plane point that `film` maps to; it starts at the
    near plane and ends at the far plane (camera-space depths)."""
    qx = c["tan_x"] * (1.0 - 2.0 * (film.x / c["width"] + c["ppo_x"]))
    qy = c["tan_y"] * (1.0 - 2.0 * (film.y / c["height"] + c["ppo_y"]))
    ux, uy = lens.x * c["radius"], lens.y * c["radius"]
    # Towards P = q f_d from u: proportional to (qx - ux / f_d, qy - uy / f_d, 1).
    dc = mi.Vector3f(qx - ux * c["inv_fd"], qy - uy * c["inv_fd"], 1.0)
    inv_len = dr.rsqrt(dr.squared_norm(dc))
    a0, a1, a2 = _axes(c, mi)
    d = dr.normalize(a0 * dc.x + a1 * dc.y + a2 * dc.z)
    o = lens_point(c, lens, mi)
    near_t, far_t = c["near"] / inv_len, c["far"] / inv_len  # depth / cos(theta)
    ray = mi.Ray3f(o + d * near_t, d)
    ray.maxt = far_t - near_t
    return ray


def shift(c, y, n, lens, mi, dr):
    """The shift of y to each lane's camera (render/camera_projection.h's shift_geometry):
    film position, lens point, film density G = f^2 |n.w| / (|n| z^3) (§4), the length of
    y -> u the camera sees (up to its near plane) and whether y's depth lies in [near, far]."""
    d0 = y - mi.Point3f(c["ox"], c["oy"], c["oz"])
    p = mi.Vector3f(c["r0x"] * d0.x + c["r0y"] * d0.y + c["r0z"] * d0.z,
                    c["r1x"] * d0.x + c["r1y"] * d0.y + c["r1z"] * d0.z,
                    c["r2x"] * d0.x + c["r2y"] * d0.y + c["r2z"] * d0.z)
    inv_z = dr.rcp(p.z)
    k = c["radius"] * (c["inv_fd"] - inv_z)
    qx, qy = p.x * inv_z + lens.x * k, p.y * inv_z + lens.y * k
    ux, uy = lens.x * c["radius"], lens.y * c["radius"]
    u = lens_point(c, lens, mi)
    film = mi.Point2f((0.5 * (1.0 - qx / c["tan_x"]) - c["ppo_x"]) * c["width"],
                      (0.5 * (1.0 - qy / c["tan_y"]) - c["ppo_y"]) * c["height"])
    w = y - u
    dist = dr.sqrt(dr.square(p.x - ux) + dr.square(p.y - uy) + dr.square(p.z))
    density = dr.square(c["f"]) * dr.abs(dr.dot(n, w)) * dr.rcp(dr.norm(n)) * inv_z * inv_z * inv_z
    visible = dist * (1.0 - c["near"] * inv_z)
    ok = (p.z >= c["near"]) & (p.z <= c["far"])
    return film, u, dr.select(ok, density, 0.0), visible, ok
