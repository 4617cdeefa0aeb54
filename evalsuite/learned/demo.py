"""Demo step: train a small FGD encoder on the demo's natural motion and score the conditions.

Runs only with the learned extra (PyTorch): without it, importing this module raises
``MissingExtraError`` and ``evalsuite demo`` skips the step, saying how to install the extra.
Reads the condition folders the score step wrote (``out_dir/conditions/<condition>/*.bvh``).
"""
from __future__ import annotations

import pathlib


def run(out_dir: pathlib.Path, echo) -> None:
    import pandas as pd

    from evalsuite.learned.fgd import score_fgd
    from evalsuite.learned.training import train_model
    from evalsuite.motion.io import load_motion

    folders = out_dir / "conditions"
    if not (folders / "natural").is_dir():
        echo("  skipped: no condition folders (the score step writes them)")
        return
    motions = {d.name: {p.stem: load_motion(p) for p in sorted(d.glob("*.bvh"))}
               for d in sorted(folders.iterdir()) if d.is_dir()}
    natural = motions.pop("natural")
    target = out_dir / "fgd"
    target.mkdir(parents=True, exist_ok=True)
    # A tiny model: 3.5 s demo segments, so 20-frame windows and a few epochs. Real use trains on
    # hours of natural motion (`evalsuite fgd train`); this only shows the workflow and the output.
    model = train_model(natural, joints="all", window=20, fps=30.0, epochs=20, seed=0, progress=False)
    model_path = target / "demo_model.pt"
    model.save(model_path)
    rows = score_fgd(model_path, natural, {"natural": natural, **motions}, raw=False, n_bootstrap=200, seed=0)
    table = pd.DataFrame(rows)
    table.to_csv(target / "fgd.csv", index=False)
    echo(f"  encoder {model.short_hash} trained on {len(natural)} natural segments (window 20 frames at 30 fps)")
    echo("  FGD per condition vs natural [bootstrap 95% percentile CI over segments; resampling biases FGD "
         "upwards, so a CI can lie above the value: docs/learned.md]")
    for row in rows:
        echo(f"  FGD {row['condition']:<11} {row['value']:9.3f}  [{row['ci_low']:.3f}, {row['ci_high']:.3f}]")
    echo(f"  written to {target}/fgd.csv and {model_path.name} (a toy model: compare conditions, not papers)")
