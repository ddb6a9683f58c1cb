"""Where the real scenes of `../shared/scenes` are, for the tests that use them.

`$MVPT_SHARED` names the `shared` folder if set; otherwise `shared/` beside the
checkout (CI's layout), or beside the folder that holds a git worktree. Tests call
`require_shared(...)`, which skips with the reason when the data is absent (a
user's clone has no `../shared`)."""
from __future__ import annotations

import os
from pathlib import Path

import pytest

_REPO = Path(__file__).resolve().parents[2]


def shared_scenes() -> Path:
    """The `shared/scenes` folder (it may not exist)."""
    env = os.environ.get("MVPT_SHARED")
    if env:
        return (Path(env) / "scenes").resolve()
    candidates = [_REPO / ".." / "shared" / "scenes", _REPO / ".." / ".." / "shared" / "scenes"]
    return next((c.resolve() for c in candidates if c.is_dir()), candidates[0].resolve())


def require_shared(rel: str = "") -> Path:
    """`shared/scenes/<rel>`, or skip the test saying what is missing."""
    p = shared_scenes() / rel
    if not p.exists():
        pytest.skip(f"shared scene data not available: {p} (place shared/ beside the checkout or set MVPT_SHARED)")
    return p
