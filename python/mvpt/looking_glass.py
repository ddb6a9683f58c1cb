"""Looking Glass devices: the quilt each one plays (its layout, views and the aspect of one
view), as Looking Glass Factory's quilt documentation gives them, and the size of a view at a
fraction of the device's own.

`mvpt render --quilt portrait` writes the quilt in a device's layout; the Blender add-on's
`Device` renders a device's views at its view size (docs/blender.md). The view cone is not a
property of the quilt: Looking Glass renders its content over about 35 to 40 degrees (the
add-on's `View cone`, 40 by default), whatever the device's optics spread them over."""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Device:
    label: str
    columns: int
    rows: int
    quilt_width: int
    quilt_height: int
    aspect: float  # one view's width / height, as the quilt's name carries it

    @property
    def views(self) -> int:
        return self.columns * self.rows

    def view_size(self, scale: float = 1.0) -> tuple:
        """(width, height) of one view at `scale` times the device's tile height, the width
        from the device's aspect (its tiles are not always of that aspect: the player
        stretches them)."""
        if not scale > 0.0:
            raise ValueError(f"the scale of a device's views must be > 0, got {scale}")
        height = max(1, round(self.quilt_height / self.rows * scale))
        return max(1, round(height * self.aspect)), height


DEVICES = {
    "portrait": Device("Looking Glass Portrait", 8, 6, 3360, 3360, 0.75),
    "go": Device("Looking Glass Go", 11, 6, 4092, 4092, 0.5625),
    "16-landscape": Device('Looking Glass 16" (landscape)', 8, 6, 7680, 4320, 1.77778),
    "16-portrait": Device('Looking Glass 16" (portrait)', 11, 6, 5995, 6000, 0.5625),
    "32-landscape": Device('Looking Glass 32" (landscape)', 7, 7, 8190, 8190, 1.777),
    "32-portrait": Device('Looking Glass 32" (portrait)', 11, 6, 8184, 8184, 0.5625),
    "65": Device('Looking Glass 65"', 8, 9, 8192, 8192, 1.777),
}


def device(name: str) -> Device:
    """The device called `name` (a key of DEVICES); ValueError naming the known ones."""
    try:
        return DEVICES[name]
    except KeyError:
        raise ValueError(f"unknown Looking Glass device '{name}': expected one of {', '.join(DEVICES)}") from None
