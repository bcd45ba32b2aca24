"""A box in a frame: ``(x, y, w, h)`` in frame pixels, (x, y) the top-left corner."""

from __future__ import annotations

Box = tuple[float, float, float, float]
"""``(x, y, w, h)`` in frame pixels, sub-pixel (a tracker's estimate, a scaled box)."""

PixelBox = tuple[int, int, int, int]
"""A :data:`Box` in whole pixels with a positive width and height: what the platform reads, records and shows."""
