"""Tiny Mitsuba 3 scenes written by the tests themselves (rectangles, cubes, diffuse, area light)."""
from __future__ import annotations

import textwrap


def sensor(id: str = "cam", res: int | str = 16, spp: int | str = 4, sampler: str = "independent",
           origin: str = "0, 1, 4", fov: str = "40", extra: str = "", film_extra: str = "", seed: int = 0) -> str:
    """One perspective sensor looking at the origin; `extra` and `film_extra` are spliced in.
    The film has a box filter unless `film_extra` names one (mvpt's default, like Mitsuba's,
    is a gaussian)."""
    if "<rfilter" not in film_extra:
        film_extra += '<rfilter type="box"/>'
    return (f'    <sensor type="perspective" id="{id}">\n'
            f'        <float name="fov" value="{fov}"/>\n'
            f'        <transform name="to_world"><lookat origin="{origin}" target="0, 0.5, 0" up="0, 1, 0"/></transform>\n'
            f'        <sampler type="{sampler}">\n'
            f'            <integer name="sample_count" value="{spp}"/>\n'
            f'            <integer name="seed" value="{seed}"/>\n'
            f'        </sampler>\n'
            f'        <film type="hdrfilm">\n'
            f'            <integer name="width" value="{res}"/>\n'
            f'            <integer name="height" value="{res}"/>{film_extra}\n'
            f'        </film>{extra}\n'
            f'    </sensor>\n')


GEOMETRY = textwrap.dedent("""\
    <bsdf type="diffuse" id="white"><rgb name="reflectance" value="0.7"/></bsdf>
    <shape type="rectangle">
        <transform name="to_world"><scale value="2"/><rotate x="1" angle="-90"/></transform>
        <ref id="white"/>
    </shape>
    <shape type="cube">
        <transform name="to_world"><scale value="0.4"/><translate y="0.4"/></transform>
        <ref id="white"/>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale value="0.5"/><rotate x="1" angle="90"/><translate y="2"/></transform>
        <emitter type="area"><rgb name="radiance" value="10"/></emitter>
    </shape>
""")


def scene(sensors: str | None = None, body: str = "", header: str = '<scene version="3.0.0">',
          geometry: str = GEOMETRY, max_depth: int = 4) -> str:
    """A complete scene: header, integrator, sensors (default: one), geometry, then `body`."""
    if sensors is None:
        sensors = sensor()
    geo = textwrap.indent(geometry, "    ")
    return (f"{header}\n"
            f'    <integrator type="path"><integer name="max_depth" value="{max_depth}"/></integrator>\n'
            f"{sensors}{geo}{body}</scene>\n")


def views(n: int, res: int = 16, spp: int = 4, sampler: str = "independent") -> str:
    """`n` sensors with ids v0..v{n-1} on a circle around the scene."""
    import math
    out = ""
    for i in range(n):
        a = 2 * math.pi * i / n
        out += sensor(id=f"v{i}", res=res, spp=spp, sampler=sampler,
                      origin=f"{3.5 * math.sin(a):.4f}, 1.5, {3.5 * math.cos(a):.4f}")
    return out


# A closed room (an inward-facing cube around everything): long paths, so one pass of
# `slow_scene()` takes a noticeable time (~0.04 s for 12 views of 64x64 on one core of 2,
# ~0.15 s at 128x128).
ROOM = GEOMETRY + textwrap.dedent("""\
    <shape type="cube">
        <transform name="to_world"><scale value="5"/></transform>
        <boolean name="flip_normals" value="true"/>
        <ref id="white"/>
    </shape>
""")


def slow_scene(n_views: int = 12, res: int = 64, spp: int = 4) -> str:
    """`n_views` views of the closed room with unbounded path depth (Russian roulette ends paths)."""
    return scene(views(n_views, res=res, spp=spp), geometry=ROOM, max_depth=-1)


def overflow_scene(res: int = 16) -> str:
    """Finite inputs whose samples overflow: a huge, bright emitter (radiance near FLT_MAX) right
    above the floor makes next-event estimates L / pdf infinite (the pdf is ~d^2 / area < 1)."""
    geometry = textwrap.dedent("""\
        <shape type="rectangle">
            <transform name="to_world"><scale value="2"/><rotate x="1" angle="-90"/></transform>
        </shape>
        <shape type="rectangle">
            <transform name="to_world"><scale value="20"/><rotate x="1" angle="90"/><translate y="1"/></transform>
            <emitter type="area"><rgb name="radiance" value="3e38"/></emitter>
        </shape>
    """)
    return scene(sensor(res=res, spp=2, origin="0, 0.5, 3", fov="60"), geometry=geometry, max_depth=3)
