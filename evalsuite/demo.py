"""``evalsuite demo``: the main job end to end on the sample data bundled in the package.

Each part of evalsuite adds one step to :data:`STEPS`; a step is a function
``run(out_dir: pathlib.Path, echo) -> None`` that reads the bundled samples (or what an
earlier step wrote into ``out_dir``) and writes its results below ``out_dir``.
"""
from __future__ import annotations

import importlib
import pathlib

import click

from evalsuite.errors import InputError

# (title, "module:function"), run in this order.
STEPS = [
    ("Motion: load the bundled BVH samples and write world positions", "evalsuite.motion.demo:run"),
    ("Score: build sample conditions and score them", "evalsuite.metrics.demo:run"),
    ("FGD: train a small motion encoder and score the conditions (needs the learned extra)",
     "evalsuite.learned.demo:run"),
    ("Render: side-by-side comparison of the sample conditions", "renderers.demo:run"),
    ("Study: build a small study from the sample stimuli and show how to serve it", "study_app.demo:run"),
    ("Analysis: analyse a simulated results.csv", "evalsuite.analysis.demo:run"),
]


@click.command()
@click.option("-o", "--out", "out_dir", type=click.Path(file_okay=False, path_type=pathlib.Path),
              default=pathlib.Path("evalsuite-demo"), show_default=True,
              help="Folder for everything the demo writes.")
def demo(out_dir: pathlib.Path):
    """Run evalsuite's main job on the bundled sample motion.

    Loads the sample BVH files shipped with evalsuite, prints their summaries and writes
    their world positions; later steps score, render, build a study and analyse results.
    """
    # Absolute, because steps write configs whose relative paths resolve against the config's folder.
    out_dir = out_dir.resolve()
    out_dir.mkdir(parents=True, exist_ok=True)
    for i, (title, target) in enumerate(STEPS, 1):
        click.secho(f"[{i}/{len(STEPS)}] {title}", bold=True)
        module_name, attr = target.split(":")
        try:
            module = importlib.import_module(module_name)
        except ImportError as exc:
            if not isinstance(exc, InputError):  # a real bug, not a missing optional extra
                raise
            click.echo(f"  skipped: {exc}")
            continue
        getattr(module, attr)(out_dir, click.echo)
    click.secho(f"Done. Everything is in {out_dir.resolve()}", fg="green")
