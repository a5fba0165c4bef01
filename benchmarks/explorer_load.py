"""``stairbounce explore`` under load, in Chromium (issue 14).

    python benchmarks/explorer_load.py [--quick] [--sessions 5] [--rounds 3]

Starts ``stairbounce explore --port 0`` in a subprocess and drives headless
Chromium (``/usr/bin/chromium``) with Playwright, loopback only, every loop
bounded.  "Action to picture" runs from the gesture (wheel zoom, drag pan)
until the page's status line reports the finished render of a new window.

1. One session: pans and zooms in the Fig. 5e window (e 0.04..0.065,
   u 0.92..0.945) at 600 x 600, max_iter 1000: median and p90; the ratio to
   the server's own work for that view (``compute_view`` + ``shade``, timed
   in this process) is the overhead of the page.
2. ``--sessions`` pages panning and zooming at once (600 x 600, max_iter
   1000, from e 0.1..0.5, u 0.4..1), plus 50 plain page GETs from a thread:
   median and p90 of both, for ``--rounds`` rounds, and the server's memory
   (RSS) after each round.
3. A cheap render (200 x 200, max_iter 300) and a tap in one session while
   another session renders 1000 x 1000 at max_iter 5000 where nothing
   slides: how much longer than the same actions alone (the wait behind
   the heavy render; target under 0.5 s).

``--quick``: one round of 3 sessions, fewer actions.  Prints the machine
load (``os.getloadavg``) with the numbers.

How it measures: each page watches itself (a 20 ms timer in the page notes
when the status line and the window boxes last changed), so the script
waits without asking the browser every 20 ms; the time to picture is from
just before the gesture to when the page showed the finished render.
Chromium, Playwright and this script run at ``--client-nice`` (default 10)
above the server: they stand for the users' own machines, and on this
2-core machine five pages' repaints (about 0.25 s of CPU per picture each)
would otherwise take the server's CPU; ``--client-nice 0`` measures them as
equals.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import random
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request
from pathlib import Path

import psutil

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--no-sandbox", "--headless", "--disable-gpu", "--disable-background-networking",
        "--disable-component-update", "--disable-sync", "--no-first-run"]
FIG5E = "?e=0.04:0.065&u=0.92:0.945&size=600x600&max_iter=1000"
MIDDLE = "?e=0.1:0.5&u=0.4:1&size=600x600&max_iter=1000"  # room to pan and zoom out
# most pixels neither slide nor lie above Cor. 2.1's bound (which the scan
# prunes without iterating): about 0.7 x 1e6 pixels x 5000 map steps
HEAVY = "?e=0.3:0.4&u=0.3:0.45&size=1000x1000&max_iter=5000"
CHEAP = "?e=0:0.4&u=0.3:1.1&size=200x200&max_iter=300"


def pct(xs, q):
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(round(q * (len(xs) - 1))))]


def summary(xs):
    ok = [x for x in xs if x is not None]
    failed = len(xs) - len(ok)
    if not ok:
        return f"no picture in {failed} tries"
    return (f"median {statistics.median(ok):.2f} s, p90 {pct(ok, 0.9):.2f} s, max {max(ok):.2f} s "
            f"(n={len(ok)}" + (f", {failed} with no picture within 120 s" if failed else "") + ")")


def load():
    return "load average " + ", ".join(f"{x:.2f}" for x in os.getloadavg())


def start_server(log: Path):
    exe = shutil.which("stairbounce", path=os.path.dirname(sys.executable)) or shutil.which("stairbounce")
    cmd = [exe] if exe else [sys.executable, "-c", "from stairbounce.cli import main; main()"]
    out = open(log, "w")
    proc = subprocess.Popen(cmd + ["explore", "--port", "0", "--no-browser"], stdout=out,
                            stderr=subprocess.STDOUT)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        text = log.read_text()
        m = re.search(r"explorer at (\S+) ", text)
        if m and "kernels ready" in text:
            return proc, m.group(1)
        if proc.poll() is not None:
            break
        time.sleep(0.2)
    proc.kill()
    raise SystemExit(f"the server did not start: {log.read_text()}")


# The page watches itself: every 20 ms a timer reads the status line and the
# window boxes (elements found once, through Panel's shadow roots) and notes
# when each last changed (Date.now()).  Asking Playwright for them every 20 ms
# instead cost Chromium about 0.7 core for 5 idle pages, a third of this
# machine, which then went missing from the server being measured.
WATCH_JS = """() => {
  if (window.__sb) return;
  const deep = (root, sel) => {
    const hit = root.querySelector(sel);
    if (hit) return hit;
    for (const el of root.querySelectorAll('*'))
      if (el.shadowRoot) { const h = deep(el.shadowRoot, sel); if (h) return h; }
    return null;
  };
  const inner = (host, sel) => host && (deep(host.shadowRoot || host, sel) || deep(host, sel));
  const w = window.__sb = {status: '', statusAt: 0, win: '', winAt: 0};
  let els = null;
  setInterval(() => {
    if (!els || !els.every(e => e.isConnected)) {
      const s = deep(document, '.sb-status');
      const e = inner(deep(document, '.sb-e-window'), 'input');
      const u = inner(deep(document, '.sb-u-window'), 'input');
      els = s && e && u ? [s, e, u] : null;
      if (!els) return;
    }
    const [s, e, u] = els;
    const spans = [...(s.shadowRoot ? s.shadowRoot.querySelectorAll('span') : []), ...s.querySelectorAll('span')];
    const status = spans.map(x => x.innerText).join(' | ');
    const win = e.value + ' ' + u.value;
    const now = Date.now();
    if (status !== w.status) { w.status = status; w.statusAt = now; }
    if (win !== w.win) { w.win = win; w.winAt = now; }
  }, 20);
}"""


async def watch(page):
    await page.evaluate(WATCH_JS)


async def status(page):
    return await page.evaluate("() => window.__sb ? window.__sb.status : ''")


async def wait_new_picture(page, before, timeout=120.0):
    """Wait (in the page) until the status reports a finished render other
    than ``before``; returns (status, the time it appeared, s since the epoch)."""
    try:
        await page.wait_for_function(
            "(before) => window.__sb && window.__sb.status.includes('computed in') && window.__sb.status !== before",
            arg=before, polling=50, timeout=timeout * 1000)
    except Exception as exc:  # Playwright's TimeoutError
        raise TimeoutError("no new picture") from exc
    got = await page.evaluate("() => [window.__sb.status, window.__sb.statusAt]")
    return got[0], got[1] / 1000.0


async def open_page(browser, url):
    page = await browser.new_page(viewport={"width": 1600, "height": 1000})
    await goto(page, url)
    return page


async def goto(page, url):
    """Load ``url`` in ``page`` and wait for its picture."""
    await page.goto(url)
    await watch(page)
    await wait_new_picture(page, None)


async def gesture(page, rng):
    """One random wheel zoom (in or out) or drag pan on the map; returns its name."""
    box = await page.locator(".bk-Canvas").first.bounding_box()
    x = box["x"] + box["width"] * rng.uniform(0.3, 0.6)
    y = box["y"] + box["height"] * rng.uniform(0.3, 0.6)
    kind = rng.choice(["zoom in", "zoom out", "pan"])
    await page.mouse.move(x, y)
    if kind == "pan":
        await page.mouse.down()
        await page.mouse.move(x + rng.uniform(-80, 80), y + rng.uniform(-80, 80), steps=5)
        await page.mouse.up()
    else:
        await page.mouse.wheel(0, -200 if kind == "zoom in" else 200)
    return kind


async def window(page):
    e, _, u = (await page.evaluate("() => window.__sb ? window.__sb.win : ''")).partition(" ")
    return e, u


async def act(page, rng):
    """A gesture and its time to the new picture (s; None: none within 120 s).
    A gesture that changes nothing (a pan against the domain's bound, a zoom
    out at e = 0) is retried: the server writes the new window into the boxes
    as soon as it accepts a request."""
    for _ in range(5):
        before, win = await status(page), await window(page)
        t0 = time.time()
        await gesture(page, rng)
        try:
            await page.wait_for_function("(win) => window.__sb.win !== win", arg=" ".join(win),
                                         polling=50, timeout=10_000)
        except Exception:  # the window did not change: try another gesture
            continue
        try:
            _, at = await wait_new_picture(page, before)
        except TimeoutError:
            return None  # counted as a failure
        return at - t0
    return None


async def one_session(browser, base, actions, rng):
    page = await open_page(browser, base + FIG5E)
    times = []
    for _ in range(actions):
        times.append(await act(page, rng))
        if times[-1] is None:
            await goto(page, base + FIG5E)
            continue
        if _ % 3 == 2:  # back to the Fig. 5e window now and then, so the view stays comparable
            await goto(page, base + FIG5E)
    await page.close()
    return times


def gets(base, n, out):
    for _ in range(n):
        t0 = time.perf_counter()
        try:
            with urllib.request.urlopen(base, timeout=120) as r:
                r.read()
        except OSError:
            out.append(None)
            continue
        out.append(time.perf_counter() - t0)


async def many_sessions(browser, base, sessions, actions, rng, n_gets=50):
    pages = await asyncio.gather(*(open_page(browser, base + MIDDLE) for _ in range(sessions)))
    get_times: list[float] = []
    th = threading.Thread(target=gets, args=(base, n_gets, get_times))
    th.start()

    async def run(page, seed):
        r = random.Random(seed)
        out = []
        for _ in range(actions):
            out.append(await act(page, r))
            if out[-1] is None:
                break  # this page stopped answering; the others go on
        return out

    results = await asyncio.gather(*(run(p, rng.random()) for p in pages))
    await asyncio.to_thread(th.join)
    for p in pages:
        await p.close()
    return [t for r in results for t in r], get_times


async def beside_heavy(browser, base, repeats):
    """Cheap renders and taps in B: alone, then while A renders the heavy view."""
    b = await open_page(browser, base + CHEAP)
    counter = iter(range(301, 10**6))

    async def cheap_round():
        times = []
        for _ in range(repeats):
            before = await status(b)
            t0 = time.time()
            await b.locator(".sb-max-iter input").fill(str(next(counter)))
            await b.locator(".sb-max-iter input").press("Enter")
            _, at = await wait_new_picture(b, before)
            times.append(at - t0)
        return times

    alone = await cheap_round()
    a = await browser.new_page(viewport={"width": 1600, "height": 1000})
    await a.goto(base + HEAVY)
    await watch(a)
    t_end = time.perf_counter() + 60
    while "%" not in await status(a) and time.perf_counter() < t_end:  # A is computing
        await asyncio.sleep(0.1)
    beside = await cheap_round()
    still = "computed in" not in await status(a)
    await a.close()
    await b.close()
    return alone, beside, still


def in_process_baseline(repeat=3):
    from dataclasses import replace

    from stairbounce.explorer.view import View, compute_view, shade

    view = View(0.04, 0.065, 0.92, 0.945, 600, 600, 1000)
    compute_view(replace(view, width=16, height=16))
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        shade(compute_view(view), view.color)
        best = min(best, time.perf_counter() - t0)
    return best


async def main_async(opts):
    from playwright.async_api import async_playwright

    rng = random.Random(14)
    with tempfile.TemporaryDirectory() as tmp:
        proc, base = start_server(Path(tmp) / "server.log")
        server = psutil.Process(proc.pid)
        # the users' browsers (and this script) stand for machines of their
        # own: lower their priority (Chromium and Playwright inherit it) so
        # that they take what CPU the server leaves, not the server's
        os.nice(opts.client_nice)
        try:
            print(f"server {base}, RSS {server.memory_info().rss / 2**20:.0f} MB after start; "
                  f"browsers at nice {os.nice(0)}, server at nice {server.nice()}; {load()}")
            async with async_playwright() as p:
                browser = await p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
                base_s = in_process_baseline()
                t1 = await one_session(browser, base, opts.actions, rng)
                ok = [t for t in t1 if t is not None] or [float("nan")]
                print(f"1 session, Fig. 5e window 600x600 max_iter 1000: action to picture {summary(t1)}; "
                      f"server work alone {base_s:.2f} s; ratio median/work "
                      f"{statistics.median(ok) / base_s:.1f}; {load()}")
                pooled = []
                for r in range(opts.rounds):
                    tm, tg = await many_sessions(browser, base, opts.sessions, opts.actions, rng, opts.gets)
                    pooled += tm
                    print(f"round {r + 1}: {opts.sessions} sessions: action to picture {summary(tm)}; "
                          f"{opts.gets} GETs {summary(tg) if tg else '-'}; server RSS {server.memory_info().rss / 2**20:.0f} MB; "
                          f"{load()}")
                if opts.rounds > 1:
                    print(f"all {opts.rounds} rounds: action to picture {summary(pooled)} "
                          f"(targets: median < 1.5 s, p90 < 3 s)")
                alone, beside, still = await beside_heavy(browser, base, opts.repeats)
                wait = [b - statistics.median(alone) for b in beside]
                print(f"cheap render (200x200, max_iter 300) alone {summary(alone)}; beside a heavy "
                      f"render (1000x1000, max_iter 5000, two thirds do not slide) {summary(beside)}; "
                      f"longest extra wait {max(wait):.2f} s (target < 0.5 s); ratio median beside/alone "
                      f"{statistics.median(beside) / statistics.median(alone):.2f}; heavy render still "
                      f"running meanwhile: {still}; {load()}")
                await browser.close()
            time.sleep(2)
            print(f"server RSS at the end {server.memory_info().rss / 2**20:.0f} MB")
        except BaseException:
            print("server log (tail):\n" + "\n".join((Path(tmp) / "server.log").read_text().splitlines()[-40:]))
            raise
        finally:
            proc.terminate()
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="1 round of 3 sessions, 4 actions each")
    ap.add_argument("--sessions", type=int, default=5)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--actions", type=int, default=6, help="gestures per session and round")
    ap.add_argument("--repeats", type=int, default=5, help="cheap renders beside the heavy one")
    ap.add_argument("--gets", type=int, default=50, help="plain page GETs during each round")
    ap.add_argument("--client-nice", type=int, default=10,
                    help="niceness added to Chromium, Playwright and this script (0: the browsers "
                         "compete with the server for the CPU as equals)")
    opts = ap.parse_args()
    if opts.quick:
        opts.sessions, opts.rounds, opts.actions, opts.repeats = 3, 1, 4, 3
    if not os.path.exists(CHROMIUM):
        raise SystemExit(f"no Chromium at {CHROMIUM}")
    asyncio.run(main_async(opts))


if __name__ == "__main__":
    main()
