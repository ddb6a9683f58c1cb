"""A frame range of a Blender scene as a shot: one view per frame, with its shutter, and the
poses of the camera and of every object over the range (docs/blender.md, "Animation").

Blender's frame f is the scene time t = (f - first) / fps seconds. With motion blur its
shutter spans `motion_blur_shutter` frames, starting at f (position START), centred on it
(CENTER) or ending at it (END); without, the frame is an instant. The scene is evaluated on a
grid of instants evenly spaced over all the shutters (at least four steps per shutter, an
integer number per frame), so that each frame's camera and each moving object get keyframes
across every shutter, which mvpt interpolates as Mitsuba does (linear scale and translation,
slerp)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from .report import Report

#: Grid steps per shutter at the least.
STEPS_PER_SHUTTER = 4


@dataclass
class Shot:
    """The frames of a range, their shutters and the poses sampled over them."""
    frames: list                 # Blender frame numbers, first to last
    fps: float
    offset: float = 0.0          # a shutter's opening, in frames from its frame
    length: float = 0.0          # a shutter's length in frames (0: an instant)
    step: float = 1.0            # the grid's step in frames
    instants: list = field(default_factory=list)  # grid instants, in frames
    camera: list = field(default_factory=list)    # the camera's world matrix at each instant
    objects: dict = field(default_factory=dict)   # instance key -> [world matrix at each instant]

    def time(self, frame: float) -> float:
        """Scene time in seconds of a (fractional) frame."""
        return (frame - self.frames[0]) / self.fps

    def shutter(self, frame: int) -> tuple[float, float]:
        """(open, close) of a frame's shutter, in seconds."""
        t0 = self.time(frame + self.offset)
        return t0, t0 + self.length / self.fps

    def within(self, frame: int) -> list:
        """Indices of the instants on frame `frame`'s shutter (one for an instant), with one more
        on each side where the shutter's ends fall between instants."""
        lo, hi = frame + self.offset, frame + self.offset + self.length
        eps = 1e-6 * self.step
        inside = [i for i, x in enumerate(self.instants) if lo - self.step + eps < x < hi + self.step - eps]
        return inside or [min(range(len(self.instants)), key=lambda i: abs(self.instants[i] - frame))]


def shot_range(scene, frames: tuple[int, int], report: Report) -> Shot:
    """The frames A..B (inclusive) of `scene` and the grid of instants their shutters need."""
    first, last = int(frames[0]), int(frames[1])
    if last < first:
        raise ValueError(f"the frame range {first}:{last} is empty (the last frame comes before the first)")
    r = scene.render
    fps = r.fps / r.fps_base
    shot = Shot(list(range(first, last + 1)), fps)
    if r.use_motion_blur and r.motion_blur_shutter > 0:
        shot.length = float(r.motion_blur_shutter)
        shot.offset = {"START": 0.0, "CENTER": -0.5 * shot.length, "END": -shot.length}[r.motion_blur_position]
        shot.step = 1.0 / math.ceil(STEPS_PER_SHUTTER / shot.length)
        if _curve_not_flat(r):
            report.warn("the motion blur's shutter curve is not converted: the shutter is open evenly")
    count = int(round((last - first + shot.length) / shot.step))
    shot.instants = [first + shot.offset + i * shot.step for i in range(count + 1)]
    return shot


def _curve_not_flat(render) -> bool:
    points = render.motion_blur_shutter_curve.curves[0].points
    return any(abs(p.location[1] - 1.0) > 1e-6 for p in points)


def instance_key(inst) -> tuple:
    """An object instance of the dependency graph, the same at every frame."""
    parent = inst.parent.name if inst.parent is not None else ""
    return (inst.object.name, parent, tuple(inst.persistent_id) if inst.is_instance else ())


def sample_poses(scene, shot: Shot, rows) -> None:
    """Evaluate the scene at each instant of the shot and record the camera's and every
    instance's world matrix (`rows`: a matrix as rows of four floats); leaves the scene at the
    first frame."""
    import bpy
    for x in shot.instants:
        frame = math.floor(x)
        scene.frame_set(frame, subframe=x - frame)
        depsgraph = bpy.context.evaluated_depsgraph_get()
        shot.camera.append(rows(scene.camera.matrix_world) if scene.camera is not None else None)
        for inst in depsgraph.object_instances:
            shot.objects.setdefault(instance_key(inst), []).append(rows(inst.matrix_world))
    scene.frame_set(shot.frames[0])


def moves(poses: list) -> bool:
    """Whether a list of matrices changes."""
    return any(p != poses[0] for p in poses[1:])
