"""Blender scenes rendered by Cycles and, converted, by mvpt agree within the statistics of
their seeds: a diffuse table-top lit by a point light, an area light, a sun, and a world
colour, each with direct light, a shadow and an inter-reflection (docs/blender.md, "How it
was checked").

Each renderer renders SEEDS independent images; the whole image's mean and each 8x8 block's
mean get a z-score from the seeds' spread (both standard errors). The test asks |z| < 4 for
the whole image and |z| < 4.5 for every one of the 16 blocks (about 1e-4 each by chance, 2e-3
for any of them), and shows its power: the same mvpt images made 10% brighter (a light's
conversion off by 10%; light transport is linear in the light's power) must fail it."""
import math

import pytest

from blender_scenes import add_light, agreement, cycles_images, mvpt_images, set_world_colour, table_scene

SEEDS = 12
Z_WHOLE, Z_BLOCK = 4.0, 4.5


def _check(name: str) -> dict:
    cy = cycles_images(SEEDS)
    mv, exported = mvpt_images(SEEDS)
    assert not exported.warnings, exported.warnings
    a = agreement(mv, cy)
    wrong = agreement(mv, cy, scale=1.1)
    print(f"\n{name}: mvpt {a['mvpt']:.5f} vs Cycles {a['cycles']:.5f}, z {a['z']:+.2f}, "
          f"largest block |z| {a['max_block_z']:.2f}; 10% brighter: z {wrong['z']:+.1f}, "
          f"largest block |z| {wrong['max_block_z']:.1f}")
    assert _passes(a), a
    assert not _passes(wrong), wrong
    return a


def _passes(a: dict) -> bool:
    return abs(a["z"]) < Z_WHOLE and a["max_block_z"] < Z_BLOCK


def test_point_light():
    table_scene()
    add_light("POINT", (1.0, -0.5, 2.5), energy=150.0, shadow_soft_size=0.0)
    _check("point")


def test_point_light_with_radius():
    table_scene()
    light = add_light("POINT", (0.6, 0.9, 1.2), energy=40.0, shadow_soft_size=0.15)
    light.data.use_soft_falloff = False  # Cycles' sphere light: what the conversion writes
    light.visible_camera = True          # in view: its radiance seen directly as well
    _check("sphere")


def test_area_light():
    table_scene()
    add_light("AREA", (0.5, -0.5, 2.0), (20, 10, 0), energy=120.0, shape="RECTANGLE", size=0.8, size_y=0.4)
    _check("area")


def test_disk_area_light():
    table_scene()
    add_light("AREA", (-0.5, 0.0, 2.0), (-15, 0, 0), energy=100.0, shape="DISK", size=0.6)
    _check("disk")


def test_sun():
    table_scene()
    add_light("SUN", (0, 0, 5), (30, 20, 0), energy=2.5, angle=0.0)
    _check("sun")


def test_world_colour():
    table_scene()
    set_world_colour((0.3, 0.4, 0.5), 1.5)
    _check("world")
