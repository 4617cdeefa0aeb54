"""``evalsuite generators list|info|check``, ``evalsuite generate`` and ``evalsuite train``."""
from __future__ import annotations

import json
import pathlib
from typing import Any

import click

from evalsuite.corpus.cli import on_mismatch_option
from evalsuite.errors import InputError
from evalsuite.generators.cli_options import device_options, joints_option
from evalsuite.generators.presets import DEFAULT_PRESET, PRESETS
from evalsuite.generators.registry import find_generator, list_generators

__all__ = ["generators", "generate_command", "train_command"]


def _parse_value(text: str) -> Any:
    try:
        return json.loads(text)
    except ValueError:
        return text


def read_config(path: str | None, settings: tuple[str, ...]) -> dict[str, Any]:
    """Options from a YAML/JSON file, then ``--set key=value`` pairs (values parsed as JSON when they are)."""
    config: dict[str, Any] = {}
    if path:
        import yaml

        try:
            data = yaml.safe_load(pathlib.Path(path).read_text(encoding="utf-8"))
        except OSError as exc:
            raise InputError(f"cannot read the config file ({exc.strerror})", path=path) from None
        except yaml.YAMLError as exc:
            mark = getattr(exc, "problem_mark", None)
            raise InputError(f"not valid YAML/JSON ({getattr(exc, 'problem', exc)})", path=path,
                             line=mark.line + 1 if mark else None) from None
        if data is not None and not isinstance(data, dict):
            raise InputError("the config file must hold a mapping of option names to values", path=path)
        config.update(data or {})
    for item in settings:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise InputError(f"--set takes key=value, got {item!r}", field="--set")
        config[key.strip()] = _parse_value(value)
    return config


def _post(items: tuple[str, ...]) -> list[Any]:
    from evalsuite.generators.runner import PostProcess

    out = []
    for item in items:
        method, _, rest = item.partition(":")
        params = []
        for kv in filter(None, rest.split(",")):
            k, sep, v = kv.partition("=")
            if not sep:
                raise InputError(f"--post takes method[:key=value,...], got {item!r}", field="--post")
            params.append((k.strip(), _parse_value(v)))
        out.append(PostProcess(method.strip(), tuple(params)))
    return out


def _load_corpus(path: str) -> Any:
    from evalsuite.corpus import load_corpus

    return load_corpus(path)


@click.group("generators")
def generators() -> None:
    """List, describe and check gesture generators (built-in, installed plug-ins, ad hoc module:Class)."""


@generators.command("list")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
def list_command(as_json: bool) -> None:
    """Every generator: built-in ones with their inputs, installed plug-ins (entry point group
    evalsuite.generators) without importing them."""
    entries = list_generators()
    if as_json:
        click.echo(json.dumps([{"name": e.name, "origin": e.origin, "target": e.target, "distribution": e.distribution,
                                "spec": e.spec.as_dict() if e.spec else None} for e in entries], indent=1))
        return
    width = max([18] + [len(e.name) for e in entries])
    for e in entries:
        if e.spec is None:
            click.echo(f"{e.name:{width}s} plug-in from {e.distribution or '?'} ({e.target}; not imported)")
            continue
        s = e.spec
        inputs = "+".join(n for n, v in (("audio", s.audio), ("text", s.transcript)) if v != "none") or "motion"
        flags = [f for f, on in (("trainable", s.trainable), ("stochastic", s.stochastic)) if on]
        fps = f"{s.native_fps:g} fps" if s.native_fps else "any fps"
        click.echo(f"{e.name:{width}s} {s.kind:17s} {inputs:10s} {fps:8s} {s.output:9s} {' '.join(flags)}")


@generators.command("info")
@click.argument("name")
def info_command(name: str) -> None:
    """Spec of one generator: citation, licence, inputs, fps, output, options, deviations from the paper."""
    e = find_generator(name)
    assert e.spec is not None
    s = e.spec
    click.echo(f"{s.name} {s.version} ({s.kind}; {e.origin}: {e.target})")
    click.echo(s.summary)
    for label, value in (("citation", s.citation), ("licence", s.license),
                         ("inputs", f"audio {s.audio}, transcript {s.transcript}, word timings {s.word_timings}"
                                    + (", speaker id" if s.speaker else "") + (", interlocutor" if s.interlocutor else "")),
                         ("output", f"{s.output} at {s.native_fps:g} fps" if s.native_fps else f"{s.output}, any fps"),
                         ("skeleton", s.skeleton or (", ".join(s.joints) if s.joints else "")),
                         ("units", s.units), ("stochastic", "yes" if s.stochastic else "no"),
                         ("trainable", "yes" if s.trainable else "no"), ("device", s.device),
                         ("needs", f"the '{s.extra}' extra" if s.extra else "")):
        if value:
            click.echo(f"  {label + ':':12s}{value}")
    if s.config:
        click.echo("  options:")
        for k, v in s.config.items():
            click.echo(f"    {k}: {v}")
    if s.deviations:
        click.echo("  deviations from the paper:")
        for d in s.deviations:
            click.echo(f"    - {d}")


@generators.command("check")
@click.argument("name")
@click.option("--config", "config_file", type=click.Path(dir_okay=False), help="Options (YAML/JSON).")
@click.option("--set", "settings", multiple=True, metavar="KEY=VALUE", help="One option (repeatable).")
@click.option("--model", type=click.Path(exists=True), help="Model folder or published model files.")
def check_command(name: str, config_file: str | None, settings: tuple[str, ...], model: str | None) -> None:
    """Run the contract's rules on a tiny synthetic corpus (trains for a few seconds when trainable and no
    --model is given); exit 1 on the first broken rule."""
    from evalsuite.generators.checking import check_generator

    for line in check_generator(find_generator(name), read_config(config_file, settings),
                                pathlib.Path(model) if model else None):
        click.echo(line)


@click.command("generate")
@click.option("-g", "--generator", "name", required=True, help="Name, module:Class or file.py:Class.")
@click.option("--corpus", type=click.Path(exists=True, file_okay=False), help="Corpus folder (any layout).")
@click.option("--split", default="test", show_default=True, help="Split(s) of the corpus, comma-separated, or all.")
@click.option("--segment", "segments", multiple=True, help="Only these segment ids (repeatable).")
@click.option("--audio", type=click.Path(exists=True, dir_okay=False), help="One utterance, without a corpus.")
@click.option("--transcript", type=click.Path(exists=True, dir_okay=False), help="Its transcript (.json/.tsv/…).")
@click.option("--model", type=click.Path(exists=True), help="Trained model folder or published model files.")
@click.option("--config", "config_file", type=click.Path(dir_okay=False), help="Options (YAML/JSON).")
@click.option("--set", "settings", multiple=True, metavar="KEY=VALUE", help="One option (repeatable).")
@click.option("--fps", type=float, default=30.0, show_default=True, help="Frame rate of the output.")
@click.option("--samples", type=int, default=1, show_default=True, help="Samples per segment (stochastic only).")
@click.option("--seed", type=int, default=0, show_default=True)
@click.option("--post", multiple=True, metavar="METHOD[:K=V,…]", help="Smoothing after generation, e.g. savgol:window=9,order=3.")
@click.option("-j", "--jobs", type=int, default=1, show_default=True, help="Local worker processes.")
@click.option("--dask", "dask_address", help="dask.distributed scheduler address.")
@click.option("--no-determinism-check", is_flag=True, help="Skip generating the first segment twice.")
@device_options
@on_mismatch_option
@click.option("-o", "--out", required=True, type=click.Path(file_okay=False), help="Output folder.")
def generate_command(name: str, corpus: str | None, split: str, segments: tuple[str, ...], audio: str | None,
                     transcript: str | None, model: str | None, config_file: str | None, settings: tuple[str, ...],
                     fps: float, samples: int, seed: int, post: tuple[str, ...], jobs: int, dask_address: str | None,
                     no_determinism_check: bool, out: str) -> None:
    """Generate motion for a corpus split (or one utterance) with a generator, under the plug-in rules.

    \b
    evalsuite generate -g mismatched --corpus corpus/ --split test --seed 7 -o out/mismatched/
    evalsuite generate -g gesticulator --model runs/gest/ --corpus corpus/ -o out/gesticulator/
    evalsuite generate -g aud2repr2pose-demo --model demo-files/ --audio speech.wav -o out/
    """
    from evalsuite.generators.requests import request_for_audio, requests_from_corpus
    from evalsuite.generators.runner import generate

    entry = find_generator(name)
    if (corpus is None) == (audio is None):
        raise InputError("give either --corpus DIR or --audio FILE.wav", field="--corpus/--audio")
    extra: dict[str, Any] = {}
    config = read_config(config_file, settings)
    assert entry.spec is not None
    if corpus is not None and "corpus" in entry.spec.config:
        config.setdefault("corpus", str(pathlib.Path(corpus).resolve()))  # generators that read the corpus itself
    if corpus is not None:
        corp = _load_corpus(corpus)
        requests = requests_from_corpus(corp, split.split(","), fps, segments=segments or None)
        extra["corpus"] = {"root": str(corp.root), "layout": corp.layout, "split": split}
    else:
        words = None
        if transcript:
            from evalsuite.corpus.transcripts import read_transcript

            words = read_transcript(transcript)
        requests = [request_for_audio(audio, fps, words)]  # type: ignore[arg-type]
        extra["audio"] = audio
    run = generate(entry, requests, out, config=config, model_dir=model, seed=seed,
                   samples=samples, post=_post(post), jobs=jobs, dask_address=dask_address,
                   check_determinism=not no_determinism_check, extra_record=extra, echo=click.echo)
    if run.cached:
        click.echo(f"{entry.name}: up to date in {out} (same generator, config, model, inputs and seed)")


@click.command("train")
@click.option("-g", "--generator", "name", required=True, help="Name, module:Class or file.py:Class.")
@click.option("--corpus", required=True, type=click.Path(exists=True, file_okay=False), help="Corpus folder.")
@click.option("--config", "config_file", type=click.Path(dir_okay=False), help="Options (YAML/JSON).")
@click.option("--set", "settings", multiple=True, metavar="KEY=VALUE", help="One option (repeatable).")
@click.option("--budget-minutes", type=float, help="Stop training after this many minutes.")
@click.option("--preset", type=click.Choice(PRESETS), default=DEFAULT_PRESET, show_default=True,
              help="Named configuration: cpu-small (evalsuite's variant, small and fast on a CPU) or paper (the "
                   "system as its paper describes it); --set/--config options override it. docs/generators.md.")
@click.option("--checkpoint-every", default="10m", show_default=True, metavar="N|Xm",
              help="Save the training's state in OUT/checkpoints every N epochs (steps) or every X minutes (10m), "
                   "and at the end of each stage; 'off': no checkpoints. Removed when training ends.")
@click.option("--resume", is_flag=True,
              help="Carry on from OUT/checkpoints (same generator, options, seed and preset): a killed training "
                   "resumed ends with the same weights as one that ran through.")
@joints_option
@device_options
@on_mismatch_option
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of weights, data order and noise.")
@click.option("-o", "--out", required=True, type=click.Path(file_okay=False), help="Model folder to write.")
def train_command(name: str, corpus: str, config_file: str | None, settings: tuple[str, ...],
                  budget_minutes: float | None, preset: str, checkpoint_every: str, resume: bool, seed: int,
                  out: str) -> None:
    """Train a generator on a corpus's train split (validation loss on its val split each epoch); writes a
    model folder with model.json (everything needed to use it) and train_log.csv.

    \b
    evalsuite train -g gesticulator --corpus corpus/ --budget-minutes 5 --seed 0 -o runs/gesticulator/
    """
    from evalsuite.generators.training import train

    entry = find_generator(name)
    result = train(entry, _load_corpus(corpus), out, seed=seed, budget_minutes=budget_minutes,
                   config=read_config(config_file, settings), preset=preset,
                   checkpoint_every=None if checkpoint_every.strip().lower() == "off" else checkpoint_every,
                   resume=resume)
    last = result.history[-1] if result.history else {}
    losses = ", ".join(f"{k} {v:.4g}" for k, v in last.items() if k.endswith("loss") and isinstance(v, float))
    click.echo(f"{name}: {len(result.history)} epochs" + (f" (last: {losses})" if losses else "") + f"; model in {out}")
