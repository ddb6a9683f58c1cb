"""End-to-end smoke test: the built-in demo loads and renders every view."""
from importlib import resources

import numpy as np

import mvpt


def test_demo_renders_all_views():
    with resources.as_file(resources.files("mvpt") / "data" / "demo.xml") as path:
        scene = mvpt.load_file(path, res=16)
    result = mvpt.render(scene, spp=2)
    assert len(result.images) == len(scene.views)
    for img in result.images.values():
        assert img.shape == (16, 16, 3) and img.dtype == np.float32
        assert np.isfinite(img).all() and img.mean() > 0
