"""mvpt: a physically based renderer for many views of one scene.

    scene = mvpt.load_file("scene.xml", spp=64)     # keyword arguments override <default>s
    result = mvpt.render(scene, spp=64, seed=1)
    result.images["0"]      # float32 (H, W, 3) linear RGB of the view with id "0"
    result.stats            # timing, ray counts, per-view statistics
    scene = mvpt.load_blend("shot.blend")           # a Blender scene (needs mvpt[blender])
"""
__version__ = "0.1.0"

__all__ = ["SceneError", "StateError", "Scene", "load_file", "load_string", "load_scene", "render", "merge", "RenderResult",
           "write_outputs", "load_blend"]

# Where each name comes from, imported on first use: `import mvpt` alone loads nothing, so the
# `mvpt` program (program.py) handles signals before NumPy and the native core load.
_FROM = {"SceneError": "_core", "Scene": "_core", "StateError": "_core", "load_file": "api", "load_string": "api",
         "load_scene": "api", "merge": "api", "render": "api", "RenderResult": "api", "write_outputs": "output",
         "load_blend": "blender.load"}


def __getattr__(name: str):
    import importlib
    if name in _FROM:
        value = getattr(importlib.import_module(f".{_FROM[name]}", __name__), name)
    else:  # a module of the package (mvpt._core, mvpt.api) not imported yet
        try:
            value = importlib.import_module(f".{name}", __name__)
        except ModuleNotFoundError as e:
            if e.name != f"{__name__}.{name}":
                raise
            raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
