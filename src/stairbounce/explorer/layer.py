"""The one interface of the explorer's map layers (issue 46 item 1).

A layer is one part of the map that :class:`~stairbounce.explorer.app.Explorer`
composes: its glyphs on the map (:meth:`Layer.build`), the work it hands to the
shared scheduler for a view, in bounded slices, and what it draws when that is
done (:meth:`Layer.draw`), its legend entry and key under the map, its line of
the status, and what a tap on it shows (:meth:`Layer.at`).  The page owns the
layout, the history and the scheduler; a layer reaches them through ``page``.
A new overlay is one new module with one subclass, listed in the page's layers.
"""

from __future__ import annotations

__all__ = ["Layer"]


class Layer:
    """Base of a map layer: ``name`` (its overlay in ``View.overlays``),
    ``legend`` (its legend label), ``css`` (the class of its status line),
    ``text`` and ``level`` (its line of the page's status: empty for none)."""

    name = ""
    legend = ""
    css = "sb-layer"  # the CSS class of its status line

    def __init__(self, page):
        self.page = page
        self.text, self.level = "", "busy"

    def build(self, fig) -> list:
        """Add the layer's glyphs to the map ``fig``; returns the renderers its
        legend entry names."""
        raise NotImplementedError

    def draw(self, view) -> None:
        """Show the layer for ``view``: what is computed at once, else its job
        on the page's scheduler (bounded slices; a new view supersedes it);
        nothing, and its job cancelled, when its overlay is off."""
        raise NotImplementedError

    def recolour(self) -> None:
        """The page's colouring changed (a layer drawn in the scan's colours
        redraws)."""

    def at(self, view, e: float, u: float):
        """What a tap at ``(e, u)`` on ``view`` reads from the layer (or None)."""
        return None

    def message(self, text: str, level: str = "busy") -> None:
        """Set the layer's line of the page's status."""
        self.text, self.level = text, level
        self.page._show_status()
