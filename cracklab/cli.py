"""Command-line entry point (``cracklab``)."""
from __future__ import annotations

import json
import sys

import click


@click.group()
@click.version_option(package_name="cracklab")
def main() -> None:
    """cracklab: spectral boundary-integral simulation of dynamic fracture."""


@main.command()
@click.option("--out", default="out", show_default=True, type=click.Path(file_okay=False),
              help="Directory to write demo output into.")
def demo(out: str) -> None:
    """Run the demonstration: Lamb's problem against Pekeris, to Zarr and PNG."""
    import cracklab.demo

    cracklab.demo.main(out=out)


def _load_scene(path: str):
    from .errors import InputError
    from .io import scene_from_data

    if path.endswith(".toml"):
        import tomllib

        try:
            with open(path, "rb") as fh:
                data = tomllib.load(fh)
        except tomllib.TOMLDecodeError as exc:
            raise InputError(path, f"not valid TOML: {exc}") from None
        return scene_from_data(data, {})
    import xarray as xr

    from .simulate import scene_of

    try:
        ds = xr.open_zarr(path, consolidated=False)
    except Exception as exc:  # noqa: BLE001 - reported as one clear line
        raise InputError(path, f"cannot open as a scene TOML or a cracklab Zarr store: {exc}") from None
    if "scene" not in ds.attrs:
        raise InputError(path, "is a Zarr store but not a cracklab run (no 'scene' attribute)")
    return scene_of(ds)


@main.command()
@click.argument("scene", type=click.Path(exists=True))
@click.option("-o", "--output", required=True, type=click.Path(), help="Zarr store to write.")
@click.option("--progress/--no-progress", default=None, help="Progress bar (default: when on a terminal).")
def run(scene: str, output: str, progress) -> None:
    """Run SCENE (a TOML scene or the Zarr store of an earlier run) into OUTPUT."""
    from .errors import InputError, SimulationError
    from .simulate import simulate

    try:
        sc = _load_scene(scene)
    except InputError as exc:
        raise click.ClickException(str(exc)) from None
    if progress is None:
        progress = sys.stderr.isatty()
    try:
        simulate(sc, progress=progress, store=output)
    except SimulationError as exc:
        raise click.ClickException(str(exc)) from None
    click.echo(f"cracklab: wrote {output}")


@main.command()
@click.option("--n1", type=int, default=256, show_default=True)
@click.option("--n3", type=int, default=256, show_default=True)
@click.option("--mode", type=click.Choice(["I", "II", "III", "shear"]), default="I", show_default=True)
@click.option("--steps", "nsteps", type=int, default=200, show_default=True)
@click.option("--engine", default="direct", show_default=True)
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object.")
def bench(n1, n3, mode, nsteps, engine, as_json) -> None:
    """Median cost per step (second half of the run) and a same-process FFT pair."""
    from .bench import run as run_bench
    from .errors import InputError

    try:
        result = run_bench(n1, n3, mode, nsteps, engine, progress=not as_json and sys.stderr.isatty())
    except InputError as exc:
        raise click.ClickException(str(exc)) from None
    if as_json:
        click.echo(json.dumps(result))
    else:
        for k, v in result.items():
            click.echo(f"{k:>22}: {v:.4g}" if isinstance(v, float) else f"{k:>22}: {v}")


if __name__ == "__main__":
    main()
