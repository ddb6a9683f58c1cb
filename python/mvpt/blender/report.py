"""What a conversion could not carry over exactly: warnings (the image changes, or something
was left out) and notes (small, stated approximations), each said once."""
from __future__ import annotations


class Report:
    def __init__(self):
        self.warnings: list[str] = []
        self.notes: list[str] = []

    def warn(self, text: str) -> None:
        if text not in self.warnings:
            self.warnings.append(text)

    def note(self, text: str) -> None:
        if text not in self.notes:
            self.notes.append(text)


class BlendError(ValueError):
    """A .blend file that cannot be converted, or Blender's module missing: one line."""
