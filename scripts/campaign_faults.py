"""The fault part of the reliability campaign (issue 17), as one script with counts.

    python scripts/campaign_faults.py            # 71 cases, 12 min on 2 shared cores at load 10
    python scripts/campaign_faults.py --full     # the report's sizes and more trials
    python scripts/campaign_faults.py --only race,damage

Every case runs the real command line in a fresh folder (a child process, as a
user would) and checks the contract docs/guide/robustness.md states ("Files, stores and
interruptions: what is guaranteed"):

- ``overwrite``: a folder of the user's at every output path, with and without
  --force; an existing file without --force.  Defect: anything deleted or
  replaced, a traceback, an exit status other than 2.
- ``unwritable``: /proc, a read-only folder, /dev/full, --dpi 100000.
  Defect: a traceback, exit status other than 2, a file left behind.
- ``race``: two tiled scans (max_iter 1000 and 300) started on one new store
  with a stagger.  Defect: both succeed, the store differs from the winner's
  in-memory scan, a traceback, or a store no later run can use.
- ``kill``: a tiled scan killed (SIGKILL / SIGINT) once k tiles are done, then
  run again.  Defect: the resumed store differs from the in-memory scan, exit
  status other than 130 for SIGINT, a temporary or lock left after the rerun.
- ``damage``: a complete store with one chunk deleted, truncated or garbled.
  Defect: the rerun does not repair it bit for bit, does not say so, or
  render/load print a traceback before the repair.
- ``ctrlc``: SIGINT to a long numba kernel (orbit diagram with a huge
  transient, scan with a huge max_iter) and to ``figures`` at several delays.
  Defect: still running 20 s later, an exit status other than 130 (or 0 when
  it had finished), a file half-written.
- ``diskfull``: a 1 MiB tmpfs (root only; skipped otherwise).  Defect: a
  traceback, exit status other than 2, a partial file.

Prints one line per case and a table of counts per part.  Exit status 1 when
any defect was found.
"""

from __future__ import annotations

import argparse
import collections
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

CLI = [sys.executable, "-c", "from stairbounce.cli import main; main()"]


def sb(args, cwd, timeout=600, **kw):
    return subprocess.run(CLI + [str(a) for a in args], cwd=cwd, capture_output=True, text=True,
                          timeout=timeout, **kw)


def traceback_in(err):
    return "Traceback" in err


def one_line(err):
    lines = [x for x in err.strip().splitlines() if not x.startswith("stairbounce: warning:")]
    return len(lines) == 1 and lines[0].startswith("stairbounce: error:")


def temporaries(folder):
    return sorted(p.name for p in Path(folder).rglob("*") if ".part" in p.name or p.name.endswith(".lock"))


class Tally:
    def __init__(self):
        self.counts = collections.defaultdict(collections.Counter)

    def case(self, part, name, ok, detail=""):
        verdict = "ok" if ok else "DEFECT"
        self.counts[part][verdict] += 1
        print(f"  [{verdict:6s}] {part:10s} {name}" + (f"  ({detail})" if detail and not ok else ""), flush=True)

    def limit(self, part, name, why):
        self.counts[part]["limit"] += 1
        print(f"  [limit ] {part:10s} {name}: {why}", flush=True)

    def skip(self, part, name, why):
        self.counts[part]["skipped"] += 1
        print(f"  [skipped] {part:10s} {name}: {why}", flush=True)

    def table(self):
        print("\n| part | cases | ok | defect | known limit | skipped |\n|---|---|---|---|---|---|")
        total = collections.Counter()
        for part, c in self.counts.items():
            n = sum(c.values())
            total.update(c)
            print(f"| {part} | {n} | {c['ok']} | {c['DEFECT']} | {c['limit']} | {c['skipped']} |")
        print(f"| all | {sum(total.values())} | {total['ok']} | {total['DEFECT']} | {total['limit']} | "
              f"{total['skipped']} |")
        return total["DEFECT"]


# --------------------------------------------------------------------------- #


WRITERS = {
    "scan --out": (["scan", "--size", "12x8", "--max-iter", "50", "--out", "{p}"], ".zarr"),
    "scan --png": (["scan", "--size", "12x8", "--max-iter", "50", "--png", "{p}"], ".png"),
    "trajectory --out": (["trajectory", "--e", "0.05", "--u", "0.93", "--steps", "2", "--dpi", "20", "--out", "{p}"], ".png"),
    "trajectory --animate": (["trajectory", "--e", "0.05", "--u", "0.93", "--steps", "1", "--dpi", "20",
                              "--out", "t.png", "--animate", "{p}"], ".gif"),
    "orbit-diagram --out": (["orbit-diagram", "--e", "0.1", "--u", "0.3:1", "--n", "10", "--transient", "10",
                             "--keep", "5", "--out", "{p}"], ".zarr"),
    "orbit-diagram --png": (["orbit-diagram", "--e", "0.1", "--u", "0.3:1", "--n", "10", "--transient", "10",
                             "--keep", "5", "--dpi", "20", "--png", "{p}"], ".png"),
    "dimension --png": (["dimension", "--resolution", "32", "--max-iter", "50", "--dpi", "20", "--png", "{p}"], ".png"),
    "render --png": (["render", "s.nc", "--png", "{p}", "--dpi", "20"], ".png"),
    "figures": (["figures", "--only", "fig3", "--dpi", "20", "--out", "f"], None),
}


def part_overwrite(t, work, args):
    for name, (cmd, suffix) in WRITERS.items():
        for force in (False, True):
            d = Path(tempfile.mkdtemp(dir=work))
            if name.startswith("render"):
                sb(["scan", "--size", "12x8", "--max-iter", "50", "--out", "s.nc"], d)
            target = d / ("f/fig3.png" if suffix is None else "out" + suffix)
            (target / "sub").mkdir(parents=True)
            (target / "sub" / "keep.txt").write_text("important")
            r = sb([a.replace("{p}", str(target)) for a in cmd] + (["--force"] if force else []), d)
            kept = (target / "sub" / "keep.txt").exists()
            t.case("overwrite", f"folder at {name}{' --force' if force else ''}",
                   kept and r.returncode == 2 and one_line(r.stderr) and not temporaries(d),
                   f"exit {r.returncode}, kept {kept}, {r.stderr.strip()[-120:]}")
        if suffix in (".png", ".zarr") and name != "figures":
            d = Path(tempfile.mkdtemp(dir=work))
            if name.startswith("render"):
                sb(["scan", "--size", "12x8", "--max-iter", "50", "--out", "s.nc"], d)
            target = d / ("old" + (".nc" if suffix == ".zarr" and name == "scan --out" else suffix))
            if name == "orbit-diagram --out":
                target = d / "old.csv"
            target.write_bytes(b"old result")
            r = sb([a.replace("{p}", str(target)) for a in cmd], d)
            t.case("overwrite", f"file at {name}",
                   target.read_bytes() == b"old result" and r.returncode == 2 and one_line(r.stderr),
                   f"exit {r.returncode}")


UNWRITABLE = [
    ["scan", "--size", "20x20", "--png", "/proc/x.png"],
    ["scan", "--size", "20x20", "--out", "/proc/x.nc"],
    ["scan", "--size", "64x64", "--tile", "32", "--out", "x.zarr", "--png", "/proc/x.png"],
    ["trajectory", "--e", "0.05", "--u", "0.93", "--out", "/proc/x.png"],
    ["trajectory", "--e", "0.05", "--u", "0.93", "--dpi", "100000"],
    ["trajectory", "--e", "0.05", "--u", "0.93", "--dpi", "5"],
    ["orbit-diagram", "--e", "0.1", "--u", "0.3:1", "--n", "50", "--out", "/proc/x.nc"],
    ["orbit-diagram", "--e", "0.1", "--u", "0.3:1", "--n", "50", "--png", "x.png", "--dpi", "100000"],
    ["dimension", "--resolution", "32", "--png", "/proc/x.png"],
    ["figures", "--only", "fig3", "--out", "/proc/figs"],
    ["figures", "--only", "fig4", "--max-iter", "3000000000"],
    ["scan", "--size", "20x20", "--scheduler", "tcp://127.0.0.1:9", "--out", "x.zarr"],
]


def part_unwritable(t, work, args):
    for cmd in UNWRITABLE:
        d = Path(tempfile.mkdtemp(dir=work))
        r = sb(cmd, d, timeout=120)
        left = sorted(p.name for p in d.iterdir())
        t.case("unwritable", " ".join(cmd), r.returncode == 2 and one_line(r.stderr) and not left,
               f"exit {r.returncode}, left {left}, {r.stderr.strip()[-160:]}")
    d = Path(tempfile.mkdtemp(dir=work))
    with open("/dev/full", "w") as full:
        r = subprocess.run(CLI + ["map", "--e", "0.1", "--u", "0.9"], cwd=d, stdout=full,
                           stderr=subprocess.PIPE, text=True)
    t.case("unwritable", "map > /dev/full", r.returncode == 2 and one_line(r.stderr), r.stderr[-160:])
    p = subprocess.Popen(CLI + ["map", "--e", "0.1", "--u", "0.9", "--steps", "20000", "--csv"], cwd=d,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    p.stdout.readline()
    p.stdout.close()
    err = p.stderr.read().decode()
    p.wait()
    t.case("unwritable", "map --csv | head -1", err == "" and p.returncode == 141, f"exit {p.returncode} {err[-120:]}")


def _store_vs_scan(store, size, max_iter):
    import xarray as xr

    from stairbounce.plane import scan

    n = int(size)
    ds = xr.open_zarr(store, consolidated=False).compute()
    ref = scan(e=(0, 1, n), u=(0, 1.5, n), max_iter=max_iter)
    try:
        xr.testing.assert_identical(ds, ref)
        return True, ""
    except AssertionError as exc:
        return False, str(exc).splitlines()[0]


def part_race(t, work, args):
    n, tile = (1024, 128) if args.full else (384, 48)
    staggers = [0.0, 0.05, 0.1, 0.2, 0.3, 0.5, 1.0] if args.full else [0.0, 0.1, 0.3]
    for stagger in staggers:
        d = Path(tempfile.mkdtemp(dir=work))
        base = CLI + ["scan", "--size", f"{n}x{n}", "--tile", str(tile), "--out", "S.zarr", "--max-iter"]
        a = subprocess.Popen(base + ["1000"], cwd=d, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        time.sleep(stagger)
        b = subprocess.Popen(base + ["300"], cwd=d, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        (_, ea), (_, eb) = a.communicate(), b.communicate()
        codes = sorted([a.returncode, b.returncode])
        ok = codes == [0, 2] and not traceback_in(ea + eb)
        detail = f"exits {a.returncode}/{b.returncode}"
        if ok:
            winner = 1000 if a.returncode == 0 else 300
            same, why = _store_vs_scan(d / "S.zarr", n, winner)
            ok = same and not temporaries(d)
            detail += f", store vs max_iter {winner} scan: {'identical' if same else why}"
        t.case("race", f"stagger {stagger} s", ok, detail)


def _wait_tiles(store, k, proc, limit=300):
    from stairbounce.atlas import tiles_done

    deadline = time.monotonic() + limit
    while time.monotonic() < deadline and proc.poll() is None:
        try:
            if tiles_done(store).sum() >= k:
                return True
        except Exception:  # noqa: BLE001 - not created yet
            pass
        time.sleep(0.05)
    return False


def part_kill(t, work, args):
    n, tile = (2048, 256) if args.full else (512, 64)
    points = [1, 8, 32, 60] if args.full else [1, 40]
    for sig in (signal.SIGKILL, signal.SIGINT):
        for k in points:
            d = Path(tempfile.mkdtemp(dir=work))
            cmd = CLI + ["scan", "--size", f"{n}x{n}", "--tile", str(tile), "--out", "S.zarr"]
            p = subprocess.Popen(cmd, cwd=d, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                 preexec_fn=_default_sigint)
            reached = _wait_tiles(d / "S.zarr", k, p)
            if p.poll() is None:
                p.send_signal(sig)
            _, err = p.communicate(timeout=120)
            expect = -signal.SIGKILL if sig == signal.SIGKILL else 130
            r = subprocess.run(cmd, cwd=d, capture_output=True, text=True)
            same, why = _store_vs_scan(d / "S.zarr", n, 1000)
            ok = (p.returncode == expect or not reached) and r.returncode == 0 and same and not temporaries(d)
            t.case("kill", f"{signal.Signals(sig).name} at {k} tiles", ok,
                   f"exit {p.returncode}, rerun {r.returncode}, {why}, left {temporaries(d)}")


def part_damage(t, work, args):
    import numpy as np

    n, tile = (2048, 256) if args.full else (256, 64)
    master = Path(tempfile.mkdtemp(dir=work)) / "S.zarr"
    cmd = ["scan", "--size", f"{n}x{n}", "--tile", str(tile), "--out"]
    sb(cmd + [master], master.parent)
    rng = np.random.default_rng(17)
    cases = []
    for var in ("status", "word_length", "period", "jumps", "impacts"):
        for how in ("delete", "truncate", "garble"):
            cases.append((var, how))
    if not args.full:
        cases = cases[::2]
    for var, how in cases:
        d = Path(tempfile.mkdtemp(dir=work))
        store = d / "S.zarr"
        shutil.copytree(master, store)
        chunks = sorted((store / var / "c").rglob("*"))
        chunks = [c for c in chunks if c.is_file()]
        c = chunks[int(rng.integers(len(chunks)))]
        if how == "delete":
            c.unlink()
        elif how == "truncate":
            c.write_bytes(b"")
        else:
            raw = bytearray(c.read_bytes())
            raw[len(raw) // 2:] = rng.integers(0, 256, len(raw) - len(raw) // 2, dtype=np.uint8).tobytes()
            c.write_bytes(bytes(raw))
        rr = sb(["render", store, "--png", d / "r.png", "--dpi", "20"], d)
        render_ok = rr.returncode in (0, 2) and not traceback_in(rr.stderr)
        r = sb(cmd + [store], d)
        said = "computed again" in r.stderr
        same, why = _store_vs_scan(store, n, 1000)
        t.case("damage", f"{how} {var}/{c.relative_to(store / var)}",
               render_ok and r.returncode == 0 and said and same,
               f"render exit {rr.returncode}, rerun {r.returncode}, said {said}, {why}")


LONG_KERNELS = {
    "orbit-diagram transient 1e12": ["orbit-diagram", "--e", "0.1", "--u", "0.3:1", "--n", "50",
                                     "--transient", "1000000000000", "--png", "x.png"],
    "scan max_iter 2e9": ["scan", "--e", "0.999:1", "--u", "0:0.001", "--size", "64x64",
                          "--max-iter", "2000000000", "--png", "x.png"],
}


def _default_sigint():
    # a child inherits an ignored SIGINT (a background job of a shell): restore it
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _signal_after(cmd, cwd, delay, sig=signal.SIGINT):
    p = subprocess.Popen(CLI + cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         preexec_fn=_default_sigint)
    time.sleep(delay)
    sent = p.poll() is None
    if sent:
        p.send_signal(sig)
    try:
        _, err = p.communicate(timeout=20)
        return p.returncode, err, sent
    except subprocess.TimeoutExpired:
        p.kill()
        p.communicate()
        return None, "still running 20 s after the signal", sent


def part_ctrlc(t, work, args):
    for name, cmd in LONG_KERNELS.items():
        for delay in ((8, 15) if args.full else (10,)):
            d = Path(tempfile.mkdtemp(dir=work))
            code, err, _ = _signal_after(cmd, d, delay)
            t.case("ctrlc", f"{name}, SIGINT at {delay} s", code == 130 and not list(d.iterdir()),
                   f"exit {code}: {err.strip()[-120:]}")
    only = "fig1,fig3,fig4,fig5a,fig6" if not args.full else "fig1,fig2,fig3,fig4,fig5,fig6,fig7"
    delays = (3.0, 4.0, 5.0, 6.0) if not args.full else tuple(2.5 + 0.25 * i for i in range(19))
    for sig in (signal.SIGINT, signal.SIGKILL):
        for delay in delays:
            d = Path(tempfile.mkdtemp(dir=work))
            cmd = ["figures", "--only", only, "--scale", "0.3", "--no-cache", "--out", "f"]
            code, err, sent = _signal_after(cmd, d, delay, sig)
            expect = 130 if sig == signal.SIGINT else -signal.SIGKILL
            finished = (d / "f" / "report.md").exists()
            # a SIGINT that lands after the work, while Python shuts down (its
            # handlers are already reset), kills the process by the signal: the
            # outputs are complete; any Python program does this
            ok = (code == expect) or (not sent and code == 0) or (finished and code == -signal.SIGINT)
            r = sb(cmd, d)  # the rerun: everything, no temporary left
            ok = ok and r.returncode == 0 and not temporaries(d / "f")
            if code == -signal.SIGINT and "importlib" in err and not (d / "f").exists() and r.returncode == 0:
                # Ctrl-C while Python still imports the package, before the
                # command's own handler exists: Python's traceback, nothing written
                t.limit("ctrlc", f"figures, SIGINT at {delay} s", "interrupted during start-up (imports)")
                continue
            t.case("ctrlc", f"figures, {signal.Signals(sig).name} at {delay} s", ok,
                   f"exit {code}, rerun {r.returncode}, left {temporaries(d / 'f')}")


def part_diskfull(t, work, args):
    d = Path(tempfile.mkdtemp(dir=work))
    if os.geteuid() != 0:
        t.skip("diskfull", "all", "mounting a tmpfs needs root")
        return
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m", "tmpfs", str(d)], capture_output=True, text=True)
    if r.returncode != 0:
        t.skip("diskfull", "all", r.stderr.strip())
        return
    try:
        cases = [
            ["scan", "--size", "512x512", "--tile", "64", "--out", "S.zarr", "--png", "S.png"],
            ["scan", "--size", "600x400", "--out", "s.zarr"],
            ["scan", "--size", "600x400", "--max-iter", "50", "--png", "s.png"],
            ["orbit-diagram", "--e", "0.1", "--u", "0.3:1", "--n", "2000", "--out", "o.csv"],
            ["trajectory", "--e", "0.05", "--u", "0.93", "--out", "t.png", "--animate", "t.gif"],
            ["figures", "--only", "fig4,fig5", "--scale", "0.5", "--no-cache", "--out", "f"],
        ]
        for cmd in cases:
            before = set(p.name for p in d.iterdir())
            r = sb(cmd, d)
            ok = r.returncode in (0, 1, 2) and not traceback_in(r.stderr) and not temporaries(d)
            if r.returncode == 2:  # figures reports its figures on stderr before the error
                last = r.stderr.strip().splitlines()[-1]
                ok = ok and last.startswith("stairbounce: error:") and "\n" not in last
            t.case("diskfull", " ".join(cmd), ok, f"exit {r.returncode}: {r.stderr.strip()[-160:]}")
            for p in set(p.name for p in d.iterdir()) - before:
                if p != "S.zarr":
                    shutil.rmtree(d / p, ignore_errors=True) if (d / p).is_dir() else (d / p).unlink()
        # the tiled store resumes once there is room
        subprocess.run(["mount", "-o", "remount,size=64m", str(d)], check=True)
        r = sb(cases[0][:-2], d)
        same, why = _store_vs_scan(d / "S.zarr", 512, 1000)
        t.case("diskfull", "tiled store resumed after ENOSPC", r.returncode == 0 and same, why)
    finally:
        subprocess.run(["umount", str(d)], check=False)


PARTS = {
    "overwrite": part_overwrite,
    "unwritable": part_unwritable,
    "race": part_race,
    "kill": part_kill,
    "damage": part_damage,
    "ctrlc": part_ctrlc,
    "diskfull": part_diskfull,
}


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--full", action="store_true", help="the report's sizes and more trials (about 30 min)")
    p.add_argument("--only", default=None, help="comma-separated parts: " + ", ".join(PARTS))
    args = p.parse_args()
    parts = list(PARTS) if not args.only else [x.strip() for x in args.only.split(",")]
    for name in parts:
        if name not in PARTS:
            p.error(f"--only: unknown part {name!r}; choose from {', '.join(PARTS)}")
    print(f"load: {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f} {os.getloadavg()[2]:.2f}")
    t = Tally()
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="stairbounce-faults-") as work:
        for name in parts:
            print(f"{name}:", flush=True)
            PARTS[name](t, Path(work), args)
    defects = t.table()
    print(f"\n{time.perf_counter() - t0:.0f} s")
    sys.exit(1 if defects else 0)


if __name__ == "__main__":
    main()
