"""mvpt: a physically based renderer for many views of one scene.

    scene = mvpt.load_file("scene.xml", spp=64)     # keyword arguments override <default>s
    result = mvpt.render(scene, spp=64, seed=1)
    result.images["0"]      # float32 (H, W, 3) linear RGB of the view with id "0"
    result.stats            # timing, ray counts, per-view statistics
"""
__version__ = "0.1.0"

from ._core import SceneError, Scene, StateError
from .api import load_file, load_string, merge, render, RenderResult
from .output import write_outputs

__all__ = ["SceneError", "StateError", "Scene", "load_file", "load_string", "render", "merge", "RenderResult", "write_outputs"]
