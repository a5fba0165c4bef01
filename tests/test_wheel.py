"""The wheel works anywhere: built by ``python -m build``, installed into a
fresh virtual environment outside the source tree, made read-only, and run.

What this proves: the wheel holds every module and the console script the
package needs (nothing is read from the checkout: the process runs in another
folder, and the test checks that ``stairbounce`` was imported from the new
environment); the package runs from a read-only folder such as another user's
site-packages, with numba's compiled code cached in the user-wide folder
instead (written on the first run, reused on the next); and every module the
package imports is a declared dependency of the wheel (core or extra).

What it does not prove: that pip resolves the declared dependencies from an
index.  To keep the test offline and quick the new environment sees the test
environment's site-packages (numpy, numba, ...) through a ``.pth`` line, and
the wheel is installed with ``--no-deps``.  (A ``.pth`` path line does not
process the ``.pth`` files inside that folder, so the test environment's
editable install of stairbounce is *not* visible there.)
"""

from __future__ import annotations

import ast
import os
import re
import shutil
import stat
import subprocess
import sys
import sysconfig
import venv
import zipfile
from importlib.metadata import packages_distributions
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.slow


def _read_only_prefix():
    """A command prefix under which the package folder really is read-only.

    ``chmod a-w`` does not stop root (CAP_DAC_OVERRIDE); dropping the
    capabilities that bypass file permissions makes root obey them."""
    if os.geteuid() != 0:
        return []
    setpriv = shutil.which("setpriv")
    if setpriv is None:
        pytest.skip("running as root without setpriv: a read-only folder cannot be simulated")
    return [setpriv, "--bounding-set=-dac_override,-dac_read_search,-fowner,-linux_immutable"]


def _normalise(name):
    return re.sub(r"[-_.]+", "-", name).lower()


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    pytest.importorskip("build")
    pytest.importorskip("hatchling")
    out = tmp_path_factory.mktemp("dist")
    r = subprocess.run([sys.executable, "-m", "build", "--wheel", "--no-isolation", "--outdir", str(out)],
                       cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    (path,) = out.glob("stairbounce-*.whl")
    return path


@pytest.fixture(scope="module")
def installed(wheel, tmp_path_factory):
    """A fresh venv with the wheel installed, its package folder read-only."""
    base = tmp_path_factory.mktemp("elsewhere")
    env_dir = base / "venv"
    venv.EnvBuilder(with_pip=False, symlinks=True).create(env_dir)
    py = env_dir / "bin" / "python"
    site = Path(subprocess.check_output(
        [str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"], text=True).strip())
    # the test environment's third-party packages, after the new venv's own
    (site / "_test_env_packages.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    r = subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "--no-index", "--quiet",
                        "--target", str(site), str(wheel)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-3000:]
    # --target puts the console script in site/bin; a normal install puts it in the venv's bin
    script = env_dir / "bin" / "stairbounce"
    shutil.move(str(site / "bin" / "stairbounce"), script)
    text = script.read_text().splitlines()
    script.write_text("\n".join([f"#!{py}"] + text[1:]) + "\n")
    script.chmod(0o755)
    package = site / "stairbounce"
    assert (package / "__init__.py").exists()
    for p in [package, *package.rglob("*")]:
        p.chmod(p.stat().st_mode & ~(stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH))
    home = base / "home"
    home.mkdir()
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "NUMBA_CACHE_DIR", "VIRTUAL_ENV", "PYTHONHOME")}
    env.update(HOME=str(home), XDG_CACHE_HOME=str(home / ".cache"), MPLBACKEND="Agg",
               PATH=f"{env_dir / 'bin'}{os.pathsep}{env.get('PATH', '')}")
    yield {"python": py, "script": script, "package": package, "home": home, "env": env, "cwd": base}
    for p in [package, *package.rglob("*")]:  # let pytest clean up
        p.chmod(p.stat().st_mode | stat.S_IWUSR)


def _run(installed, args, timeout=300):
    r = subprocess.run(_read_only_prefix() + [str(a) for a in args], cwd=installed["cwd"],
                       env=installed["env"], capture_output=True, text=True, timeout=timeout)
    assert r.returncode == 0, f"{args}:\n{r.stdout[-3000:]}\n{r.stderr[-3000:]}"
    return r.stdout


SESSION = """
import sys, stairbounce as sb, stairbounce.plane as plane
from pathlib import Path
print("FILE", sb.__file__)
w = sb.sliding_word(0.05, 0.93)
assert w.letters == (2, 2, 2), w          # the paper's Fig. 5e neighbourhood
ds = sb.scan((0.0, 1.0, 40), (0.0, 1.5, 30), max_iter=200)
c = sb.scan_coords(ds.e.values, ds.u.values, max_iter=200)
assert (c.word_length.values == ds.word_length.values).all()
lo, hi = sb.tongue(1, 0.5)
assert sb.sliding_word(0.5, (lo + hi) / 2).letters == (1,)   # Theorem 3.1
sb.plot.plot_scan(ds).figure.savefig("session.png")
assert Path("session.png").stat().st_size > 0
hits = plane._scan_fast.stats.cache_hits
print("HITS", sum(hits.values()))
"""


def test_wheel_runs_from_a_read_only_install_outside_the_source_tree(installed):
    package = installed["package"]
    with pytest.raises(PermissionError):  # the folder really is read-only for the runs below
        _probe_write(package)
    # one figure (the plane: scan, exact borders, report), compiled in the empty user cache;
    # that the wheel holds every file of the package is test_the_wheel_holds_every_file_of_the_package's
    out = _run(installed, [installed["script"], "figures", "--only", "fig4", "--out", "figs", "--scale", "0.25"])
    assert "wrote 1 figure" in out
    figs = installed["cwd"] / "figs"
    assert (figs / "fig4.png").stat().st_size > 0
    assert (figs / "report.md").exists()

    first = _run(installed, [installed["python"], "-c", SESSION])
    assert f"FILE {package / '__init__.py'}" in first  # the wheel, not the checkout
    # numba could not write next to the read-only package: the cache is in the user-wide folder
    user_cache = installed["home"] / ".cache" / "numba"
    index_files = list(user_cache.rglob("*.nbi"))
    assert index_files, f"no numba cache under {user_cache}"
    assert not list(package.rglob("*.nbi"))
    # the second run loads the compiled kernel from there instead of compiling again
    second = _run(installed, [installed["python"], "-c", SESSION])
    assert int(re.search(r"HITS (\d+)", second).group(1)) >= 1


def _probe_write(folder):
    """Raise PermissionError when this process, as the runs see it, cannot write in ``folder``."""
    r = subprocess.run(_read_only_prefix() + [sys.executable, "-c",
                       f"open({str(folder / 'probe')!r}, 'w')"], capture_output=True, text=True)
    if "PermissionError" in r.stderr:
        raise PermissionError(r.stderr.strip().splitlines()[-1])
    (folder / "probe").unlink(missing_ok=True)


def test_every_import_of_the_package_is_a_declared_dependency(wheel):
    with zipfile.ZipFile(wheel) as z:
        meta = z.read(next(n for n in z.namelist() if n.endswith(".dist-info/METADATA"))).decode()
        sources = {n: z.read(n).decode() for n in z.namelist() if n.endswith(".py")}
    declared = {_normalise(re.match(r"[A-Za-z0-9_.\-]+", line.split(":", 1)[1].strip()).group(0))
                for line in meta.splitlines() if line.startswith("Requires-Dist:")}
    imported = set()
    for text in sources.values():
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.Import):
                imported |= {a.name.split(".")[0] for a in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                imported.add(node.module.split(".")[0])
    third_party = imported - set(sys.stdlib_module_names) - {"stairbounce"}
    dists = packages_distributions()
    undeclared = {}
    for module in sorted(third_party):
        names = {_normalise(d) for d in dists.get(module, [])}
        if not names & declared:
            undeclared[module] = sorted(names)
    assert not undeclared, f"imported but not declared in the wheel's metadata: {undeclared}"
    # and the wheel's entry point is the command line
    with zipfile.ZipFile(wheel) as z:
        entry = z.read(next(n for n in z.namelist() if n.endswith("entry_points.txt"))).decode()
    assert "stairbounce = stairbounce.cli:console" in entry


def test_the_wheel_holds_every_file_of_the_package(wheel):
    """Every file under src/stairbounce that git tracks (modules, data, the type marker) is
    in the wheel, and the wheel holds no other package file."""
    tracked = subprocess.run(["git", "ls-files", "src/stairbounce"], cwd=ROOT, capture_output=True, text=True)
    if tracked.returncode != 0:
        pytest.skip("not a git checkout: the tracked files cannot be listed")
    want = {Path(f).relative_to("src").as_posix() for f in tracked.stdout.split()}
    assert "stairbounce/structure/_kernel.py" in want and "stairbounce/py.typed" in want
    with zipfile.ZipFile(wheel) as z:
        got = {n for n in z.namelist() if n.startswith("stairbounce/")}
    assert got == want, f"only in the wheel: {sorted(got - want)}; only in the source: {sorted(want - got)}"


def test_wheel_carries_the_one_version_and_the_type_marker(wheel):
    from stairbounce._version import __version__

    assert wheel.name.startswith(f"stairbounce-{__version__}-")
    with zipfile.ZipFile(wheel) as z:
        names = z.namelist()
        meta = z.read(next(n for n in names if n.endswith(".dist-info/METADATA"))).decode()
        # the license travels with the wheel (hatch copies LICENSE into the .dist-info)
        assert any(n.endswith(".dist-info/licenses/LICENSE") for n in names), names
    assert f"\nVersion: {__version__}\n" in meta
    assert "stairbounce/py.typed" in names
