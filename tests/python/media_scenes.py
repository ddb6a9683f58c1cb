"""Small scenes with participating media for the tests: a fog ball or box on a floor under an
environment and a light, seen by two sensors, and `.vol` grids written on the fly."""
from __future__ import annotations

import struct
from pathlib import Path

import numpy as np


def write_vol(path, data: np.ndarray) -> Path:
    """A Mitsuba .vol file of `data` shaped (nz, ny, nx, channels), float32, box [0, 1]^3."""
    nz, ny, nx, c = data.shape
    with open(path, "wb") as f:
        f.write(b"VOL" + bytes([3]) + struct.pack("<iiiii", 1, nx, ny, nz, c) + struct.pack("<6f", 0, 0, 0, 1, 1, 1))
        f.write(np.ascontiguousarray(data, dtype="<f4").tobytes())
    return Path(path)


def blob_grid(n: int = 16, channels: int = 1) -> np.ndarray:
    """A smooth off-centre density with a denser slab at x > 0.7 (so orientation matters)."""
    z, y, x = np.meshgrid(*[(np.arange(n) + 0.5) / n] * 3, indexing="ij")
    blob = np.exp(-((x - 0.5) ** 2 + (y - 0.45) ** 2 + (z - 0.5) ** 2) / 0.05) + 0.3 * (x > 0.7)
    if channels == 1:
        return blob[..., None]
    return np.stack([blob, blob ** 2, 0.5 * blob + 0.2], -1)


SENSORS = """
  <sensor type="perspective"><float name="fov" value="45"/>
    <transform name="to_world"><lookat origin="0.5, 1.5, 5" target="0, 0.2, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="24"/><rfilter type="box"/></film>
    {medium}
  </sensor>
  <sensor type="perspective"><float name="fov" value="35"/>
    <transform name="to_world"><lookat origin="4, 1, -2" target="0, 0.2, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/><rfilter type="box"/></film>
    {medium}
  </sensor>"""

LIGHTS = """
  <emitter type="constant"><rgb name="radiance" value="0.3, 0.35, 0.4"/></emitter>
  <shape type="sphere"><point name="center" x="1" y="2.5" z="1"/><float name="radius" value="0.3"/>
     <emitter type="area"><rgb name="radiance" value="20, 18, 15"/></emitter></shape>
  <emitter type="point"><point name="position" x="-2" y="3" z="2"/><rgb name="intensity" value="6, 6, 8"/></emitter>
  <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="4"/><translate y="-1.01"/></transform>
     <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.5, 0.4"/></bsdf></shape>"""


def medium_xml(medium: tuple, name: str) -> str:
    """A (type, body) medium as an element with `name` (interior, exterior, or a sensor's)."""
    return f'<medium type="{medium[0]}" name="{name}">{medium[1]}</medium>'


def fog_scene(medium: tuple, boundary: str = '<bsdf type="null"/>', shape: str = "sphere", max_depth: int = 64,
              sensor_medium: str = "", extra: str = "", integrator: str = "volpath") -> str:
    """`medium` (type, body): the inside of a ball or cube bounded by `boundary`, on a floor, two sensors."""
    geometry = ('<point name="center" x="0" y="0.2" z="0"/><float name="radius" value="0.9"/>' if shape == "sphere"
                else "")
    return f"""<scene version="3.0.0">
  <integrator type="{integrator}"><integer name="max_depth" value="{max_depth}"/></integrator>
  {SENSORS.format(medium=sensor_medium)}
  {LIGHTS}
  <shape type="{shape}">{geometry}{boundary}
     {medium_xml(medium, "interior")}
  </shape>
  {extra}
</scene>"""


def homogeneous(params: str, phase: str = "") -> tuple:
    return "homogeneous", params + phase


def heterogeneous(vol: Path, params: str, phase: str = "") -> tuple:
    """A grid on the cube [-1, 1]^3 (the `cube` shape)."""
    return "heterogeneous", (f'<volume type="gridvolume" name="sigma_t"><string name="filename" value="{vol}"/>'
                             '<transform name="to_world"><scale value="2"/><translate x="-1" y="-1" z="-1"/></transform>'
                             f'</volume>{params}{phase}')
