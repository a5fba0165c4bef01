"""Cascades of words: a family of words with one block raised to a free exponent,
its members located exactly on a line of the (e, u) plane, and its scaling law.

A *pattern* is written as the paper writes words, with one block raised to a
free exponent: ``(1^k, 0^inf)`` is the family ``(1, 0^inf)``, ``(1, 1, 0^inf)``,
``(1, 1, 1, 0^inf)``, ...; ``((1, 0)^k, 1, 1, 0^inf)`` raises the block
``(1, 0)``.  A zero written just before the tail belongs to the tail
(``0, 0^inf`` is ``0^inf``), so ``((1, 0)^k, 0^inf)`` is ``(1, 0, ..., 1, 0^inf)``.

**The order that makes the search exact (proven).**  Along a fixed itinerary
every event margin ``T - v - C s`` decreases strictly with u and with e
(:mod:`stairbounce.structure.verify`, "Monotonicity").  On a line e = const
(or u = const) the impact number of step ``j`` is the number of margins of that
step that are >= 0 (sliding: all of them), so among points that share the
impact numbers of steps ``1..j-1`` it is a non-increasing function of u; by
induction the set of points with a given prefix is an interval, and the
sequence of impact numbers of the orbit of ``(1, 0)`` (sliding ranked above
every finite number) is *lexicographically non-increasing* along the line.
Hence (i) each word's set on the line is one interval, and (ii) at any point
the first step where the orbit leaves a word's impact numbers says on which
side of the point the word's interval lies (more impacts than the word there:
the word lies at larger u).  So a member is found by bisection on that sign
(:func:`_search`), its two edges are shrunk to adjacent floats with the
secant/bisection of :func:`stairbounce.structure.borders._shrink_secant` and labelled
with :func:`stairbounce.structure.borders._first_difference` (graze / edge / chatter and
the step, as :func:`stairbounce.border_points` labels them), and member k+1 is
searched beyond member k on the side the order of their words gives: nothing
is sampled, so a member narrower than any grid is not missed, and a member that
is not found has no float on the line (its interval is empty or narrower than
the float spacing: the bisection ends on two adjacent floats that both
differ from it).  The same order bounds the accumulation point: every member
with large k has the first N impact numbers of the limit itinerary (prefix,
then the block forever), and the points with that prefix form one interval
I_N, so the limit of the members lies in the closure of I_N for every N.

The search relies on the float map reproducing the exact order, which it does
except within a few ulps of a border (rounding), so every statement here holds
"to rounding", as for :func:`stairbounce.border_points`.

The package, one module per idea (layers: each imports only those above it):

- :mod:`.patterns`: patterns, letters, impact numbers, their order, a word's family;
- :mod:`.search`: the compiled bisection on a line, edges, enclosures, words at points;
- :mod:`.laws`: the scaling law of widths and positions, known accumulation curves;
- :mod:`.members`: a cascade's members on a line, and their number against e;
- :mod:`.families`: the families of a line or a window, organising centres;
- :mod:`.farey`: the Farey / Stern-Brocot test.
"""

from .patterns import Family, family_of, word_impacts
from .laws import CascadeLaw, cascade_law
from .members import Cascade, cascade, member_count
from .families import cascades, organising_centres, window_families
from .farey import FareyTest, farey_test

__all__ = ["Cascade", "CascadeLaw", "Family", "FareyTest", "cascade", "cascade_law", "cascades",
           "family_of", "farey_test", "member_count", "organising_centres", "word_impacts",
           "window_families"]
