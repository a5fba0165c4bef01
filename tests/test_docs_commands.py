"""The command lines the documentation shows are the command lines that work.

Every ``stairbounce ...`` line of a fenced block of README.md and of the pages
under docs/ (a ```` ```bash ```` or ```` ```text ```` block, ``\\`` continuations
joined, ``# comments`` dropped) is

* **parsed** by the real command line (Typer/click): the command exists, every
  option exists and every value converts (a notation of the docs is read as a
  reader reads it: ``[--opt X]`` is an optional part, parsed with the rest;
  ``A|B`` is a choice, parsed with A; ``...`` stands for options shown on
  the line above, and the rest of the line is parsed);
* **run** in a fresh temporary folder per page, in the page's order (so that a
  command may read what an earlier one wrote), with its sizes made tiny by
  :data:`TINY`: each size option the line gives is capped, and where the line
  relies on a large default, the tiny value is added (:data:`ADDED`); an output
  that costs time whatever the sizes is left out (:data:`LEFT_OUT`).  A line is not run only
  for a reason :func:`not_run` states (a server, a cluster, the whole paper,
  a file no earlier line writes), and every such line is still parsed.

Every ``stairbounce ...`` in an inline code span is checked for its command
and option names (it may be a fragment: ``stairbounce dimension --png``).
docs/guide/cli.md lists every command of the application (a test generates
the list from the Typer app).  docs/development.md describes this mechanism.
"""

from __future__ import annotations

import importlib
import re
import shlex
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import pytest

typer = pytest.importorskip("typer")

from stairbounce.cli import app, main  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
# the changelog records commands as they were at each version
PAGES = [ROOT / "README.md", *sorted(p for p in DOCS.rglob("*.md")
                                     if "_build" not in p.parts and p.name != "changelog.md")]
CLI = typer.main.get_command(app)
# click, or the copy of it that recent Typer versions vendor: its Context and exceptions
_Context = CLI.context_class
UsageError = importlib.import_module(_Context.__module__.rsplit(".", 1)[0] + ".exceptions").UsageError

# The tiny sizes a documented command runs with: an option the line gives is
# capped at this value; ADDED gives the options added where a command's default
# is large (per command, and per --method for `dimension`).
TINY = {"--size": 48, "--resolution": 64, "--max-iter": 200, "--points": 2000, "--lines": 8,
        "--n": 40, "--transient": 100, "--keep": 50, "--steps": 200, "--tile": 16, "--scale": 0.05,
        "--proven-depth": 6}
# options left out of a run (each still parsed): the trajectory's GIF takes tens of
# seconds whatever the sizes (tests/test_cli_model.py writes one)
LEFT_OUT = {"--animate": "the GIF animation"}
ADDED = {
    "scan": ["--size", "48x34", "--max-iter", "200"],
    "borders": ["--size", "48x48", "--max-iter", "200"],
    "words": ["--size", "48x48", "--max-iter", "200"],
    "orbit-diagram": ["--n", "40", "--transient", "100", "--keep", "50"],
    "motion": ["--steps", "200", "--transient", "100"],
    "itinerary": ["--max-iter", "200"],
    ("dimension", "uncertainty"): ["--points", "2000", "--max-iter", "200", "--eps", "1e-4:0.1:7"],
    ("dimension", "boxes"): ["--resolution", "64", "--max-iter", "200"],
    ("dimension", "slicing"): ["--lines", "8", "--max-iter", "200"],
}

_FENCE = re.compile(r"^ {0,3}(`{3,}|~{3,})(.*)$")
_SHELL_KINDS = {"bash", "sh", "shell", "console", "text", ""}


@dataclass(frozen=True)
class Command:
    page: Path
    line: int
    text: str  # as the page shows it (continuations joined), after "stairbounce"
    block: bool  # in a fenced block (parsed and run), or an inline code span (names checked)

    def __str__(self):
        return f"{self.page.relative_to(ROOT)}:{self.line}: stairbounce {self.text}"


def documented_commands(page: Path) -> list[Command]:
    """Every ``stairbounce ...`` of one page, in the page's order."""
    lines = page.read_text().splitlines()
    found: list[Command] = []
    fence = kind = None
    i = 0
    while i < len(lines):
        line = lines[i]
        m = _FENCE.match(line)
        if m and fence is None:
            fence, kind = m.group(1), (m.group(2).strip().split() or [""])[0]
        elif fence is not None and line.strip().startswith(fence) and not line.strip().strip(fence[0]):
            fence = kind = None
        elif fence is not None:
            text = line.strip().removeprefix("$ ")
            if kind in _SHELL_KINDS and (text == "stairbounce" or text.startswith("stairbounce ")):
                start = i
                while text.endswith("\\") and i + 1 < len(lines):
                    i += 1
                    text = text[:-1].rstrip() + " " + lines[i].strip()
                found.append(Command(page, start + 1, text.removeprefix("stairbounce").strip(), True))
        else:
            for span in re.findall(r"`(stairbounce(?: [^`]*)?)`", line):
                found.append(Command(page, i + 1, span.removeprefix("stairbounce").strip(), False))
        i += 1
    return found


ALL = [c for page in PAGES for c in documented_commands(page)]
BLOCKS = [c for c in ALL if c.block]


def _tokens(cmd: Command, *, optional: bool) -> list[str]:
    """The arguments of the line as the shell splits them; ``[...]`` parts kept
    (``optional=True``) or left out, ``A|B`` read as ``A``, ``...`` left out."""
    text = cmd.text
    text = re.sub(r"\[([^\]]*)\]", (lambda m: m.group(1)) if optional else "", text)
    out = []
    for tok in shlex.split(text, comments=True):
        if tok == "...":
            continue
        if "|" in tok and not tok.startswith("-"):
            tok = tok.split("|", 1)[0]
        out.append(tok)
    return out


def _resolve(args: list[str]) -> tuple[list[str], object, list[str]]:
    """The command path (``["cache", "info"]``), the click command and its arguments."""
    names: list[str] = []
    command: object = CLI
    rest = list(args)
    while hasattr(command, "commands") and rest and not rest[0].startswith("-"):
        sub = command.get_command(_Context(command), rest[0])
        assert sub is not None, f"no command {' '.join([*names, rest[0]])!r}"
        names.append(rest.pop(0))
        command = sub
    return names, command, rest


def _option_names(command: object) -> set[str]:
    return {o for p in command.params for o in (*p.opts, *p.secondary_opts)} | {"--help"}


def parse(args: list[str]):
    """What the shell would start: ``stairbounce ARGS`` parsed and converted, not run."""
    names, command, rest = _resolve(args)
    parent = _Context(CLI, info_name="stairbounce") if names else None
    return command.make_context(" ".join(["stairbounce", *names]), rest, parent=parent)


def not_run(cmd: Command, folder: Path) -> str | None:
    """Why a documented line is parsed but not run (None: it runs)."""
    args = _tokens(cmd, optional=False)
    names, command, rest = _resolve(args)
    if "..." in cmd.text:
        return "it stands for the options of the line above (...)"
    if names == ["explore"]:
        return "it starts a web server (the explorer's browser tests serve it)"
    if names == ["figures"]:
        return "it makes every figure of the paper, about a minute (tests/test_figures.py runs the recipes)"
    if "--scheduler" in rest or "--workers" in rest:
        return "it needs a Dask cluster (tests/test_atlas.py runs tiled scans on one)"
    for opt, value in zip(rest, rest[1:]):
        # (certify --store writes its store: run, so that the lines below can read it)
        if opt in ("--store", "--image") and names != ["certify"] and not (folder / value).exists():
            return f"it reads {value}, which no line above it on the page writes"
    for value in rest:
        if names == ["render"] and not value.startswith("-") and value.endswith(".zarr") \
                and not (folder / value).exists():
            return f"it reads {value}, which no line above it on the page writes"
    return None


def tiny(args: list[str]) -> list[str]:
    """The line's arguments with every size capped by :data:`TINY` and the tiny
    values of :data:`ADDED` where the line leaves a large default."""
    names, command, rest = _resolve(args)
    out = list(rest)
    for opt in LEFT_OUT:
        while opt in out:
            i = out.index(opt)
            del out[i:i + 2]
    flags = {o for p in command.params if getattr(p, "is_flag", False) for o in p.opts}
    for i, opt in enumerate(out[:-1]):
        if opt not in TINY or opt in flags:  # (orbit-diagram's --points is a flag)
            continue
        cap, value = TINY[opt], out[i + 1]
        if opt == "--size":
            w, h = (int(x) for x in value.lower().split("x"))
            k = min(1.0, cap / max(w, h))
            out[i + 1] = f"{max(2, round(w * k))}x{max(2, round(h * k))}"
        elif isinstance(cap, float):
            out[i + 1] = str(min(float(value), cap))
        else:
            out[i + 1] = str(min(int(value), cap))
    key: str | tuple[str, str] = " ".join(names)
    if names == ["dimension"]:
        method = out[out.index("--method") + 1] if "--method" in out else (
            "uncertainty" if ("--points" in out or "--eps" in out) else "boxes" if "--resolution" in out
            else "slicing")  # the options of a method select it, as the command does
        key = ("dimension", method)
    added = ADDED.get(key, [])
    for opt, value in zip(added[::2], added[1::2]):
        if opt not in out:
            out += [opt, value]
    return [*names, *out]


def test_the_pages_show_commands():
    # the reader's commands: enough of them that this test means something
    assert len(BLOCKS) >= 40 and len({c.page for c in BLOCKS}) >= 8, len(BLOCKS)


@pytest.mark.parametrize("cmd", BLOCKS, ids=str)
def test_every_documented_command_line_parses(cmd):
    for optional in (True, False):
        try:
            parse(_tokens(cmd, optional=optional))
        except (typer.Exit):  # --version, --help: eager, and fine
            pass
        except UsageError as exc:
            pytest.fail(f"{cmd}\n  {exc.format_message()}")


@pytest.mark.parametrize("cmd", [c for c in ALL if not c.block], ids=str)
def test_every_inline_command_names_a_command_and_its_options(cmd):
    words = shlex.split(re.sub(r"\[[^\]]*\]|\.\.\.", " ", cmd.text))
    names: list[str] = []
    command: object = CLI
    while hasattr(command, "commands") and words and not words[0].startswith("-"):
        choices = words.pop(0).split("|")
        subs = [command.get_command(_Context(command), name) for name in choices]
        assert all(subs), f"{cmd}: no command {words!r}"
        names.append(choices[0])
        command = subs[0]
    unknown = {w.split("=")[0] for w in words if w.startswith("--")} - _option_names(command)
    assert not unknown, f"{cmd}: stairbounce {' '.join(names)} has no option {sorted(unknown)}"


@pytest.mark.slow
@pytest.mark.parametrize("page", sorted({c.page for c in BLOCKS}), ids=lambda p: str(p.relative_to(ROOT)))
def test_every_documented_command_runs_on_a_tiny_window(page, tmp_path, monkeypatch, capsys):
    # a fresh folder per page, the commands in the page's order; the figures'
    # cache in that folder too (`cache clear` must not empty the user's)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    ran, skipped = [], []
    for cmd in (c for c in BLOCKS if c.page == page):
        reason = not_run(cmd, tmp_path)
        if reason:
            skipped.append(f"{cmd}: {reason}")
            continue
        args = tiny(_tokens(cmd, optional=False))
        t0 = time.perf_counter()
        with pytest.raises(SystemExit) as exc:
            main(args)
        out, err = capsys.readouterr()
        print(f"{time.perf_counter() - t0:6.2f} s  stairbounce {shlex.join(args)}", file=sys.__stderr__)
        assert exc.value.code in (0, None), f"{cmd}\n  ran as: stairbounce {shlex.join(args)}\n  {err.strip()}"
        ran.append(cmd)
    # a page's lines are run unless each says why not (and each of those is parsed above)
    assert ran or skipped
    for entry in skipped:
        assert entry.rsplit(": ", 1)[1]


def test_the_runner_caps_sizes_and_adds_tiny_defaults():
    # the line's --size capped, and --max-iter, which it leaves at 1000, added
    assert tiny(["scan", "--size", "800x800", "--e", "0:1"]) == ["scan", "--size", "48x48", "--e", "0:1",
                                                                 "--max-iter", "200"]
    assert tiny(["scan"]) == ["scan", "--size", "48x34", "--max-iter", "200"]
    assert tiny(["dimension", "--method", "boxes", "--resolution", "500"]) == \
        ["dimension", "--method", "boxes", "--resolution", "64", "--max-iter", "200"]
    assert tiny(["word", "--e", "0.05", "--u", "0.93"]) == ["word", "--e", "0.05", "--u", "0.93"]
    assert tiny(["trajectory", "--e", "0.05", "--u", "0.93", "--animate", "t.gif", "--steps", "6"]) == \
        ["trajectory", "--e", "0.05", "--u", "0.93", "--steps", "6"]
    # a flag of the same name as a size elsewhere is left alone
    assert tiny(["orbit-diagram", "--u", "0.6", "--e", "0:0.5", "--points"])[:6] == \
        ["orbit-diagram", "--u", "0.6", "--e", "0:0.5", "--points"]
    # the notation: optional parts, choices, "..." and comments
    cmd = Command(ROOT / "README.md", 1, "figures [--out f] [--format png|pdf] ... # all", True)
    assert _tokens(cmd, optional=True) == ["figures", "--out", "f", "--format", "png"]
    assert _tokens(cmd, optional=False) == ["figures"]


def test_a_wrong_documented_option_is_caught():
    # what the parse test would report for a line with an option that does not exist
    with pytest.raises(UsageError, match="No such option"):
        parse(["orbit-diagram", "--e", "0.1", "--u", "0.3:1.3", "--no-such-option"])
    with pytest.raises(UsageError):
        parse(["scan", "--max-iter", "many"])
    with pytest.raises(AssertionError, match="no command"):
        parse(["no-such-command"])


def test_the_cli_page_lists_every_command():
    # generated from the Typer application: a new command must be added to the page
    listed = {tuple(_resolve(_tokens(c, optional=True))[0])
              for c in documented_commands(DOCS / "guide" / "cli.md") if c.block}
    every = set()
    for name, command in CLI.commands.items():
        if getattr(command, "hidden", False):
            continue
        if hasattr(command, "commands"):
            every |= {(name, sub) for sub in command.commands}
        else:
            every.add((name,))
    assert len(every) >= 14
    missing = sorted(" ".join(c) for c in every - listed)
    assert not missing, f"docs/guide/cli.md does not show: {missing}"
