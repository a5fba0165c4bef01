"""``stairbounce cascade``: a family of words with one block raised to a free
exponent, its members located exactly on a line of the plane, and its law
(:mod:`stairbounce.cascades`)."""

from __future__ import annotations

from pathlib import Path

import typer

from ._app import FORCE_HELP, CLIError, app, check_outputs, parse_range

E_HELP = "Restitution coefficient: a number (the line e = const) or a range MIN:MAX (a line u = const)."
U_HELP = "Horizontal speed (normalised): a range MIN:MAX (the line e = const) or a number."


def _line(e: str, u: str):
    """``--e``/``--u`` as (number, range) in either order; CLIError otherwise."""
    e_range, u_range = ":" in e, ":" in u
    if e_range == u_range:
        raise CLIError(f"give one of --e and --u as a range MIN:MAX and the other as a number, "
                       f"got --e {e!r} --u {u!r}")
    if e_range:
        try:
            fixed = float(u)
        except ValueError:
            raise CLIError(f"--u must be a number, got {u!r}") from None
        return parse_range("e", e), fixed
    try:
        fixed = float(e)
    except ValueError:
        raise CLIError(f"--e must be a number, got {e!r}") from None
    return fixed, parse_range("u", u)


@app.command("cascade", short_help="Members of a family of words, exactly, and its law.")
def cascade_(
    pattern: str = typer.Argument(..., help='The family, e.g. "(1^k, 0^inf)" or "((1, 0)^k, 1, 1, 0^inf)".'),
    e: str = typer.Option("0.02", "--e", help=E_HELP),
    u: str = typer.Option("0.6:0.75", "--u", help=U_HELP),
    k_max: int = typer.Option(100, "--k-max", help="Largest exponent tried (1..1000000, and the work within the limit the guide states: refused before it starts)."),
    law_k: str = typer.Option(None, "--law-k", help="Members the law is fitted on, KLO:KHI (default: the last 8)."),
    max_iter: int = typer.Option(1000, "--max-iter", help="Steps to name the words just outside each edge (>= 1)."),
    rows: int = typer.Option(60, "--rows", help="Members printed (all go to --out)."),
    count: bool = typer.Option(False, "--count", help="Count the members exactly: at --e (a number), or "
                               "every e in --e MIN:MAX where the count changes (--u a range, MIN:MAX)."),
    n: int = typer.Option(32, "--n", help="With --count and a range of e: e values checked before bisecting (>= 2)."),
    prove: bool = typer.Option(False, "--prove", help="Prove each member's interval with certify_box "
                               "(interval arithmetic over the segment of the line) and say which are proven."),
    out: Path = typer.Option(None, "--out", help="The members as .csv (one row per member)."),
    force: bool = typer.Option(False, "--force", help=FORCE_HELP),
):
    """Every member of the family that exists on the line, each interval's edges located
    to rounding and labelled by their event, where the members accumulate, why the
    next member does not exist, and the law of the widths (geometric or algebraic)."""
    from .._io import atomic_path
    from ..cascades import cascade

    if count:
        _count(pattern, e, u, k_max, n, out, force)
        return
    ev, uv = _line(e, u)
    k_range = None
    if law_k is not None:
        parts = law_k.split(":")
        if len(parts) != 2 or not all(p.strip().isdigit() for p in parts):
            raise CLIError(f"--law-k must be KLO:KHI (integers), got {law_k!r}")
        k_range = (int(parts[0]), int(parts[1]))
    if rows < 0:
        raise CLIError(f"--rows must be >= 0, got {rows}")
    if out is not None:
        if out.suffix.lower() != ".csv":
            raise CLIError(f"--out must end in .csv, got {str(out)!r}")
        check_outputs(force, out=out)
    c = cascade(pattern, e=ev, u=uv, k_max=k_max, max_iter=max_iter, law_k=k_range)
    typer.echo(c.text(max_rows=rows))
    members = c.members
    if prove:
        proofs = c.prove()
        typer.echo(_proofs_text(c, proofs, rows))
        members = members.merge(proofs[["k", "proven", "lo", "hi", "share"]].rename(
            columns={"lo": "proven_lo", "hi": "proven_hi", "share": "proven_share"}), on="k", how="left")
    if out is not None:
        with atomic_path(out, overwrite=force) as tmp:
            members.to_csv(tmp, index=False)
        typer.echo(f"wrote {out}")


def _proofs_text(c, proofs, rows):
    """``--prove``: which members are proven, over which segment."""
    other = "u" if c.axis == "e" else "e"
    whole = int((proofs.proven & (proofs.share == 1.0)).sum())
    inner = int((proofs.proven & (proofs.share < 1.0)).sum())
    lines = [f"proven members (basis: proven, sb.certify_box: every decision of the orbit of (1, 0) by "
             f"outward-rounded interval arithmetic over every real point of the segment {other} = "
             f"{c.fixed:g}, {c.axis} in [lo, hi]; the member's float interval, or the part left after "
             "cutting 1e-9..0.1 of its width at each end):",
             f"{'k':>4} {c.axis + ' lo':>20} {c.axis + ' hi':>20} {'share':>11}  verdict"]
    for i, r in enumerate(proofs.itertuples()):
        if i == rows:
            lines.append(f"... {len(proofs) - rows} more")
            break
        if r.proven:
            lines.append(f"{r.k:>4} {r.lo:>20.17g} {r.hi:>20.17g} {r.share:>11.9f}  proven")
        else:
            lines.append(f"{r.k:>4} {'':>20} {'':>20} {'':>11}  not proven ({r.status}"
                         + (f": {r.reason} at step {r.step}" if r.reason else "") + ")")
    lines.append(f"{whole + inner} of {len(proofs)} member(s) proven: {whole} over the whole float interval, "
                 f"{inner} over an inner part; {len(proofs) - whole - inner} not proven (numerical only)")
    return "\n".join(lines)


def _count(pattern, e, u, k_max, n, out, force):
    """``--count``: the member count at one e, or its changes over a range of e."""
    from .._io import atomic_path
    from ..cascades import member_count

    if ":" not in u:
        raise CLIError(f"--u must be a range MIN:MAX with --count, got {u!r}")
    uv = parse_range("u", u)
    if ":" in e:
        ev = parse_range("e", e)
    else:
        try:
            ev = float(e)
        except ValueError:
            raise CLIError(f"--e must be a number or a range MIN:MAX, got {e!r}") from None
    if out is not None:
        if out.suffix.lower() != ".csv":
            raise CLIError(f"--out must end in .csv, got {str(out)!r}")
        check_outputs(force, out=out)
    res = member_count(pattern, ev, uv, k_max=k_max, n=n)
    if not isinstance(res, int):
        typer.echo(f"members of {pattern} on lines e = const, u in [{uv[0]:g}, {uv[1]:g}], "
                   f"e in [{ev[0]:g}, {ev[1]:g}] (counts to rounding, numerical: each member's existence is a "
                   "float decision; changes bisected to adjacent floats of e):")
        typer.echo(f"{'k':>5} {'e below':>22} {'e above':>22}  change      count below -> above")
        for r in res.itertuples():
            typer.echo(f"{r.k:>5} {r.e_below:>22.17g} {r.e_above:>22.17g}  "
                       f"{'appears' if r.appears else 'disappears':<11} {r.count_below} -> {r.count_above}")
        typer.echo(f"{len(res)} change(s); counts at the {n} values of e checked first: "
                   + ", ".join(f"{c}" for _, c in res.attrs["counts"]))
        if out is not None:
            with atomic_path(out, overwrite=force) as tmp:
                res.to_csv(tmp, index=False)
            typer.echo(f"wrote {out}")
        return
    typer.echo(f"{res} member(s) of {pattern} on the line e = {ev:g}, u in [{uv[0]:g}, {uv[1]:g}] "
               "(to rounding, numerical: each member's existence is a float decision)")
