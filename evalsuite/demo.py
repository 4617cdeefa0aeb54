"""``evalsuite demo``: the main job from speech to statistics, on a synthetic speaker it makes itself.

Steps (:data:`evalsuite.pipeline.steps.STEPS`): synthesise a corpus, train the re-implemented seed systems for
a short budget, generate the test split with them and the built-in conditions, score (FGD included), render
side-by-side videos with the speech, build a study, simulate participants (stated as a simulation), analyse,
correlate the metrics with the ratings. Each step prints what it wrote; a summary table closes the run.
"""
from __future__ import annotations

import pathlib
import time

import click

from evalsuite.pipeline.steps import STEPS, DemoSettings


def _summary(s: DemoSettings, times: list[tuple[str, float]]) -> list[str]:
    import pandas as pd

    lines = ["", "step                 seconds"]
    lines += [f"{title.split(':')[0]:20s} {sec:7.1f}" for title, sec in times]
    lines.append(f"{'total':20s} {sum(sec for _, sec in times):7.1f}")
    summary = s.out / "score" / "summary.csv"
    if summary.is_file():
        table = pd.read_csv(summary)
        table["value"] = pd.to_numeric(table["value"], errors="coerce")
        keep = ["fgd", "energy_speed_r", "beat_a2m", "hellinger_speed", "jerk", "mse", "lexical_contrast_wide"]
        table = table[table.metric.isin(keep)].pivot_table(index="condition", columns="metric", values="value")
        lines += ["", "condition scores (score/summary.csv):", table.round(3).to_string()]
    corr = s.summary.get("correlations")
    if corr is not None and len(corr):
        top = corr.sort_values("spearman_rho", key=abs, ascending=False).head(6)
        lines += ["", "metrics vs simulated ratings (correlate/correlations.csv, top by |rho|):",
                  top[["metric", "human_measure", "n", "spearman_rho", "kendall_tau_b"]].round(3).to_string(index=False)]
    return lines


@click.command()
@click.option("-o", "--out", "out_dir", type=click.Path(file_okay=False, path_type=pathlib.Path),
              default=pathlib.Path("evalsuite-demo"), show_default=True, help="Folder for everything the demo writes.")
@click.option("--minutes", type=float, default=6.0, show_default=True, help="Minutes of synthetic speech.")
@click.option("--budget-minutes", type=float, default=1.0, show_default=True,
              help="Training budget of each re-implemented system.")
@click.option("--demo-model", type=click.Path(exists=True, file_okay=False, path_type=pathlib.Path), default=None,
              help="Folder of the published Aud2Repr2Pose demo model's files: adds it as a condition.")
@click.option("--seed", type=int, default=0, show_default=True)
def demo(out_dir: pathlib.Path, minutes: float, budget_minutes: float, demo_model: pathlib.Path | None,
         seed: int) -> None:
    """Run the main job from speech to statistics on a synthetic speaker (about 10 minutes on 2 cores).

    \b
    evalsuite demo                      # everything into evalsuite-demo/
    evalsuite demo --minutes 2 --budget-minutes 0.2 -o quick/   # a quick look
    """
    try:  # the generators and FGD need torch: say so before doing anything
        import torch  # noqa: F401
    except ImportError:
        raise click.ClickException('the demo trains gesture generators and FGD encoders, which need PyTorch: '
                                   'pip install "evalsuite[learned]" (torch 2.13.0, CPU build), or run '
                                   "`bash scripts/demo`, which installs it") from None
    s = DemoSettings(out=out_dir.resolve(), minutes=minutes, budget_minutes=budget_minutes, seed=seed,
                     demo_model=demo_model.resolve() if demo_model else None)
    s.out.mkdir(parents=True, exist_ok=True)
    times = []
    for i, (title, step) in enumerate(STEPS, 1):
        click.secho(f"[{i}/{len(STEPS)}] {title}", bold=True)
        t0 = time.perf_counter()
        step(s, click.echo)
        times.append((title, time.perf_counter() - t0))
    for line in _summary(s, times):
        click.echo(line)
    (s.out / "summary.txt").write_text("\n".join(_summary(s, times)) + "\n", encoding="utf-8")
    click.secho(f"Done. Everything is in {s.out}", fg="green")
