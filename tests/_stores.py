"""Tiled stores cut short, as a killed scan leaves them."""


class StopAfter(Exception):
    pass


def stop_after(k):
    """A progress callback that interrupts the scan once k tiles are complete."""

    def progress(done, total):
        if done >= k:
            raise StopAfter(done)

    return progress
