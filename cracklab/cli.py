"""Command-line entry point (``cracklab``)."""

import click


@click.group()
def main() -> None:
    """cracklab: spectral boundary-integral simulation of dynamic fracture."""


@main.command()
@click.option("--out", default="out", show_default=True, type=click.Path(file_okay=False),
              help="Directory to write demo output into.")
def demo(out: str) -> None:
    """Run the demonstration simulation."""
    import cracklab.demo

    cracklab.demo.main(out=out)


if __name__ == "__main__":
    main()
