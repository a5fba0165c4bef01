"""The explorer's map layers share one interface (issue 46 item 1,
``explorer/layer.py``): the page composes them, draws each for every view,
recolours them and shows each one's status line.  A new overlay is one
subclass added to ``page.layers``; this test adds one."""

from __future__ import annotations

import pytest

from stairbounce.explorer import view as V

pytest.importorskip("panel", reason="panel is in the web extra")


def test_the_page_composes_its_layers_and_a_new_one_needs_no_page_change():
    from stairbounce.explorer.app import Explorer
    from stairbounce.explorer.borders_layer import BordersLayer
    from stairbounce.explorer.layer import Layer
    from stairbounce.explorer.proven_layer import ProvenLayer
    from stairbounce.explorer.scheduler import Scheduler

    class Counting(Layer):
        """A layer that schedules one slice per view and says how many it drew."""

        name, css = "counting", "sb-counting"

        def __init__(self, page):
            super().__init__(page)
            self.views, self.recoloured = [], 0

        def build(self, fig):
            return []

        def draw(self, view):
            def work():
                yield
                return view

            self.page._sched.submit(self.page, "counting", work(),
                                    on_done=lambda v, err, job: self._done(v))

        def _done(self, view):
            self.views.append(view)
            self.message(f"counted {len(self.views)} views", "info")

        def recolour(self):
            self.recoloured += 1

    sched = Scheduler(thread=False)
    app = Explorer(V.View(0.0, 1.0, 0.0, 1.5, 24, 24, max_iter=50), scheduler=sched)
    assert [type(lay) for lay in app.layers] == [BordersLayer, ProvenLayer]
    assert all(isinstance(lay, Layer) for lay in app.layers)
    extra = Counting(app)
    app.layers.append(extra)
    app.start()
    sched.run_all()
    assert extra.views == [app.view]
    assert '<span class="sb-info sb-counting" style="color:#1a5e1a">counted 1 views</span>' in app.status.object
    app.color.value = "period"
    assert extra.recoloured == 1
    app._goto(app.view.with_window(0.1, 0.9, 0.2, 1.2))
    sched.run_all()
    assert [v.e_lo for v in extra.views] == [0.0, 0.1] and "counted 2 views" in app.status.object
    # the built-in layers' lines are theirs: a message of one shows under its class
    app.proven.message("a proven line", "warning")
    assert 'class="sb-warning sb-proven"' in app.status.object
    with pytest.raises(NotImplementedError):
        Layer(app).draw(app.view)
