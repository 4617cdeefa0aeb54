"""``evalsuite import-judgements FORMAT FILE -o results.csv``: another tool's judgements as a results.csv."""
from __future__ import annotations

import pathlib

import click

from evalsuite.analysis.importers import IMPORTERS, import_judgements, write_results


def _formats_help() -> str:
    return "; ".join(f"{name}: {IMPORTERS.get(name).summary}" for name in IMPORTERS.names())


@click.command("import-judgements")
@click.argument("fmt", metavar="FORMAT")
@click.argument("file", type=click.Path(dir_okay=False, path_type=pathlib.Path))
@click.option("-o", "--out", type=click.Path(dir_okay=False, path_type=pathlib.Path),
              default=pathlib.Path("results.csv"), show_default=True,
              help="The results.csv to write (read by `evalsuite analyze` and `evalsuite correlate --results`).")
@click.option("--study", default=None,
              help="Study id written on every row (default: the file's name; for the evalsuite format: the study "
                   "to keep from a file holding several).")
@click.option("--question", default=None,
              help="Question id for every row when the file does not name one (default: human-likeness for "
                   "ratings, preference for pairwise votes).")
def import_judgements_command(fmt, file, out, study, question):
    """Convert human judgements in FORMAT (see docs/human-data.md) from FILE into evalsuite's results.csv."""
    df = import_judgements(fmt, file, study=study, question=question)
    write_results(df, out)
    kinds = df["page_type"].value_counts().to_dict()
    click.echo(f"{len(df)} judgements ({', '.join(f'{n} {k}' for k, n in sorted(kinds.items()))}) from "
               f"{df['participant'].nunique()} participants -> {out}")


import_judgements_command.help = (import_judgements_command.help or "") + "\n\nFormats: " + _formats_help()
