"""The colours of the three kinds of border (and of the window's sides), defined
once for every output: the ``borders`` PNG (plot/borders.py), the orbit
diagram's border ticks (plot/orbits.py), the explorer's border points and
traced arcs, and the SVG export of traced regions (structure.export.regions_svg).

They lie outside the word-length palette of the scans (black, then the turbo
map from blue through cyan, green, yellow and orange to dark red;
plot/plane.py), away from white (no sliding solution) and from the tongues'
magenta: each is at least 60 CIELAB units from every colour of that palette
and 40 from white and the magenta (numerical: computed against
``plot.plane.color_key("word_length")``; tests/test_regions_export.py checks
40 from all of them), so an arc drawn over a scan does not take the colour of
a band.  A plain module without plotting imports: the
core's SVG export reads it too.
"""

KIND_COLOURS = {"graze": "#8000ff", "edge": "#ff1493", "chatter": "#0f5a00", "window": "#8c8c8c"}
"""Colour of each kind of border (and of the window's sides)."""

KIND_COLOUR_NAMES = {"graze": "violet", "edge": "pink", "chatter": "dark green", "window": "grey"}
"""What to call them in a legend."""


def kinds_legend(kinds=("graze", "edge", "chatter")) -> str:
    """``"graze violet, edge pink, chatter dark green"``: the legend's words for ``kinds``."""
    return ", ".join(f"{k} {KIND_COLOUR_NAMES[k]}" for k in kinds)
