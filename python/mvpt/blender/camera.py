"""The scene camera and render settings as a Mitsuba 3 sensor and integrator.

Blender's camera looks down its local -Z with +Y up and +X to the right; Mitsuba's looks
down +Z with +Y up and +X to the left, so to_world is the camera's matrix times a half turn
about Y. The field of view follows the sensor fit: Auto spans the sensor width over the
larger image side (fov_axis "larger"), Horizontal the width over x, Vertical the height over
y, with fov = 2 atan(sensor / (2 lens)). Shift (in units of the larger image side) becomes
Mitsuba's principal point offset (in units of the image's width and height). Depth of field:
a thin lens of aperture radius lens / (2 f-stop) focused at the focus distance (or object).
Resolution x percentage, Cycles' samples, bounces and pixel filter: docs/blender.md, "What
converts"."""
from __future__ import annotations

import math

from .report import Report
from .xml_writer import Element, animation, plugin

HALF_TURN_Y = ((-1, 0, 0, 0), (0, 1, 0, 0), (0, 0, -1, 0), (0, 0, 0, 1))

# Standard deviation of Cycles' Blackman-Harris window of width 1 px (its four-term window over
# [-w/2, w/2]), integrated numerically: a Gaussian of this deviation stands in for it.
BLACKMAN_HARRIS_STDDEV = 0.1385


def _matmul(a, b):
    return tuple(tuple(sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)) for i in range(4))


def resolution(scene) -> tuple[int, int]:
    r = scene.render
    scale = r.resolution_percentage / 100.0
    return max(1, int(r.resolution_x * scale)), max(1, int(r.resolution_y * scale))


def _fov(cam) -> tuple[float, str]:
    fit = cam.sensor_fit
    if fit == "VERTICAL":
        return 2 * math.degrees(math.atan(cam.sensor_height / (2 * cam.lens))), "y"
    fov = 2 * math.degrees(math.atan(cam.sensor_width / (2 * cam.lens)))
    return fov, ("x" if fit == "HORIZONTAL" else "larger")


def _shift(cam, width: int, height: int, extra_x: float = 0.0) -> tuple[float, float]:
    """Blender's shift (fractions of the larger side; +x moves the view right, +y up), plus
    `extra_x` (a stereo eye's), as Mitsuba's principal point offsets (fractions of width and
    height, added to the film position, whose y runs down the image)."""
    side = max(width, height)
    return (cam.shift_x + extra_x) * side / width, -cam.shift_y * side / height


def stereo_eyes(scene, report: Report) -> list:
    """The eyes of Blender's stereoscopy (Output > Views > Stereo 3D), each (view name, its pose
    in the camera's frame as 4x4 rows, its extra horizontal shift): the eyes sit on the camera's
    x axis the interocular distance apart (around the pivot: both half-way, or one at the camera),
    and converge at the convergence distance by a shift (Off-Axis, Blender's default: shift
    (interocular / sensor width) (lens / convergence distance) per unit of offset), by turning
    towards it (Toe-in), or not at all (Parallel). Empty without stereoscopy."""
    r = scene.render
    if not r.use_multiview:
        return []
    if r.views_format != "STEREO_3D":
        report.warn("multi-view rendering with cameras per view ('Multi-View') is not converted: the scene "
                    "camera alone is rendered")
        return []
    cam = scene.camera.data
    stereo = cam.stereo
    e, c = stereo.interocular_distance, max(stereo.convergence_distance, 1e-6)
    eyes = []
    for name, left in (("left", True), ("right", False)):
        view = r.views.get(name)
        if view is None or not view.use:
            continue
        pivot_eye = (stereo.pivot == "LEFT" and left) or (stereo.pivot == "RIGHT" and not left)
        fac = 0.0 if pivot_eye else 0.5 if stereo.pivot == "CENTER" else 1.0
        signed = fac if left else -fac
        shift = (e / cam.sensor_width) * (cam.lens / c) * signed if stereo.convergence_mode == "OFFAXIS" else 0.0
        # The left eye on the camera's -x side; toe-in turns it right (about +y, towards +x).
        turn = -math.atan(e * signed / c) if stereo.convergence_mode == "TOE" else 0.0
        eyes.append((name, _eye_pose(-e * signed, turn), shift))
    return eyes


def _eye_pose(x: float, turn: float = 0.0) -> tuple:
    """A view's pose in the camera's frame (4x4 rows): `x` along the camera's x axis, turned by
    `turn` radians about its y axis."""
    c, s = math.cos(turn), math.sin(turn)
    return ((c, 0.0, s, x), (0.0, 1.0, 0.0, 0.0), (-s, 0.0, c, 0.0), (0.0, 0.0, 0.0, 1.0))


def quilt_eyes(cam, views: int, cone_deg: float, distance: float) -> list:
    """The views of a Looking Glass quilt of the camera `cam` (its data), as stereo_eyes gives
    them: `views` cameras on the camera's x axis whose directions from the focal point, at
    `distance` ahead, span the view cone `cone_deg` evenly (view 0 the leftmost, at -cone/2,
    as the quilt's first tile), each shifted so that the focal plane is the same in every view
    (Looking Glass's convention: the camera's focus distance is the plane that appears on the
    display's surface)."""
    eyes = []
    for i in range(views):
        angle = math.radians(cone_deg) * (i / (views - 1) - 0.5) if views > 1 else 0.0
        x = distance * math.tan(angle)
        shift = -(x / distance) * (cam.lens / cam.sensor_width)  # the focal point back to the middle
        eyes.append((f"view{i:02d}", _eye_pose(x), shift))
    return eyes


def sensor(scene, report: Report, spp: int, ident: str = "camera", shutter=None, poses=None, eye=None,
           size=None) -> Element:
    """The <sensor> of the scene's camera, with its film and sampler: at its current pose, or,
    for a frame of a shot, open over `shutter` (open, close) in seconds with the camera's
    world matrices `poses` [(time, rows)] as its keyframes (one: a still pose); `eye`, a
    stereo eye of stereo_eyes, moves and shifts it as that eye; `size` (width, height) renders
    it at that size instead of the scene's resolution, as Blender would."""
    obj = scene.camera
    width, height = size or resolution(scene)
    if obj is None or obj.type != "CAMERA":
        raise ValueError("the scene has no camera")
    cam = obj.data
    where = f"camera '{obj.name}'"
    if cam.type != "PERSP":
        report.warn(f"{where}: {cam.type} cameras cannot be converted; rendered as a perspective camera")
    if scene.render.pixel_aspect_x != scene.render.pixel_aspect_y:
        report.warn(f"{where}: a pixel aspect ratio other than 1 is not converted")
    dof = cam.dof.use_dof and cam.dof.aperture_fstop > 0
    s = plugin("sensor", "thinlens" if dof else "perspective", ident)
    fov, axis = _fov(cam)
    s.float("fov", fov).string("fov_axis", axis)
    s.float("near_clip", cam.clip_start).float("far_clip", cam.clip_end)
    ppx, ppy = _shift(cam, width, height, eye[2] if eye else 0.0)
    if ppx or ppy:
        s.float("principal_point_offset_x", ppx).float("principal_point_offset_y", ppy)
    if dof:
        _thin_lens(s, obj, cam, report, where)
    if shutter is not None:
        s.float("shutter_open", shutter[0]).float("shutter_close", shutter[1])
    local = _matmul(eye[1], HALF_TURN_Y) if eye else HALF_TURN_Y
    if poses is not None and len(poses) > 1:
        s.add(animation("to_world", [(t, _matmul(_rigid(m), local)) for t, m in poses]))
    else:
        s.matrix("to_world", _matmul(_rigid(poses[0][1] if poses else obj.matrix_world), local))
    sampler = s.add(plugin("sampler", "independent"))
    sampler.add(Element("integer", name="sample_count", value="$spp"))
    sampler.integer("seed", scene.cycles.seed if hasattr(scene, "cycles") else 0)
    film = s.add(plugin("film", "hdrfilm"))
    film.add(Element("integer", name="width", value="$width"))
    film.add(Element("integer", name="height", value="$height"))
    film.add(_filter(scene, report))
    return s


def _rigid(matrix):
    """The camera's world matrix without scale (Blender ignores a camera's scale)."""
    m = [list(row) for row in matrix]
    for j in range(3):
        n = math.sqrt(sum(m[i][j] ** 2 for i in range(3))) or 1.0
        for i in range(3):
            m[i][j] /= n
    return m


def focus_distance(obj) -> float:
    """The camera object's focus distance: its focus object's distance along the view axis, or
    its Focus Distance."""
    dof = obj.data.dof
    if dof.focus_object is None:
        return dof.focus_distance
    to_target = dof.focus_object.matrix_world.translation - obj.matrix_world.translation
    forward = -obj.matrix_world.col[2].xyz.normalized()
    return max(to_target.dot(forward), 1e-4)


def _thin_lens(s: Element, obj, cam, report: Report, where: str) -> None:
    dof = cam.dof
    distance = focus_distance(obj)
    if dof.aperture_blades > 0:
        report.warn(f"{where}: its {dof.aperture_blades}-bladed aperture is rendered round")
    if dof.aperture_ratio != 1:
        report.warn(f"{where}: its anamorphic aperture ratio {dof.aperture_ratio:g} is rendered round")
    s.float("aperture_radius", cam.lens * 1e-3 / (2 * dof.aperture_fstop)).float("focus_distance", distance)


def _filter(scene, report: Report) -> Element:
    cycles = getattr(scene, "cycles", None)
    kind = cycles.pixel_filter_type if cycles is not None else "BLACKMAN_HARRIS"
    width = cycles.filter_width if cycles is not None else 1.5
    if kind == "BOX":
        if width != 1:
            report.note(f"the box pixel filter of width {width:g} px is one pixel wide (Mitsuba's box)")
        return plugin("rfilter", "box")
    stddev = width * BLACKMAN_HARRIS_STDDEV if kind == "BLACKMAN_HARRIS" else width / 6
    report.note(f"the pixel filter {kind} of width {width:g} px is a gaussian of standard deviation "
                f"{stddev:.3g} px")
    return plugin("rfilter", "gaussian").float("stddev", stddev)


def integrator(scene, report: Report) -> Element:
    """Mitsuba's path integrator with Cycles' bounce limit: Cycles' `max_bounces` counts the
    bounces after the first hit, Mitsuba's `max_depth` the path's segments, so
    max_depth = max_bounces + 2 (docs/blender.md)."""
    cycles = getattr(scene, "cycles", None)
    bounces = cycles.max_bounces if cycles is not None else 12
    if cycles is not None:
        limits = {k: getattr(cycles, k + "_bounces") for k in ("diffuse", "glossy", "transmission")}
        lower = {k: v for k, v in limits.items() if v < bounces}
        if lower:
            report.note("Cycles' per-kind bounce limits (" + ", ".join(f"{k} {v}" for k, v in lower.items())
                        + f") are not converted: every path may bounce {bounces} times")
        if cycles.sample_clamp_direct > 0 or cycles.sample_clamp_indirect > 0:
            report.note("Cycles' sample clamping is not converted (mvpt does not clamp: no bias, more noise)")
    i = plugin("integrator", "path")
    i.add(Element("integer", name="max_depth", value="$max_depth"))
    return i


def max_depth(scene) -> int:
    cycles = getattr(scene, "cycles", None)
    return (cycles.max_bounces if cycles is not None else 12) + 2


def samples(scene) -> int:
    cycles = getattr(scene, "cycles", None)
    return int(cycles.samples) if cycles is not None else 128
