"""Mutation fuzzing of the three kinds of user input: results.csv, study definitions and BVH files.

Starts from a valid file of each kind (the bundled simulated ``sample_results.csv``, the demo study
definition over placeholder clips, a small synthetic BVH), mutates it (byte flips, truncation, deleted,
duplicated and repeated lines, huge numbers, injected quotes, misspelt keywords, a giant field, very many
columns) and runs the command a user would run on it (``evalsuite analyze --no-figures``,
``evalsuite study build``, ``evalsuite info``), each in a forked process with a time limit. Every outcome
is one of:

- ``accepted``: exit 0 (fine when the mutation left the file valid; listed so that a person can judge);
- ``clean``: a one-line error (an ``InputError`` through the CLI); ``long message`` counts those over 300
  characters;
- ``traceback``: any other exception escaped;
- ``hang``: still running after ``--timeout`` seconds (killed); ``slow`` counts runs over ``--slow``.

    python benchmarks/fuzz_inputs.py                  # 60 inputs of each kind, seed 0
    python benchmarks/fuzz_inputs.py -n 200 --seed 3 --show traceback,hang,slow

Bounded: ``-n`` inputs per kind, one process at a time, each killed after ``--timeout`` seconds; every
file lives in a temporary folder that is removed. The figures depend on the seed and the machine's load.
"""
from __future__ import annotations

import argparse
import collections
import multiprocessing as mp
import os
import pathlib
import random
import re
import shutil
import sys
import tempfile
import time

LONG_MESSAGE = 300


# ------------------------------------------------------------------------------------------ mutations

def _lines(data: bytes) -> list[bytes]:
    return data.split(b"\n")


def byte_flip(rng: random.Random, data: bytes) -> bytes:
    b = bytearray(data)
    for _ in range(rng.randint(1, 3)):
        b[rng.randrange(len(b))] = rng.randrange(256)
    return bytes(b)


def truncate(rng: random.Random, data: bytes) -> bytes:
    return data[: rng.randrange(1, len(data))]


def delete_line(rng: random.Random, data: bytes) -> bytes:
    lines = _lines(data)
    del lines[rng.randrange(len(lines))]
    return b"\n".join(lines)


def duplicate_line(rng: random.Random, data: bytes) -> bytes:
    lines = _lines(data)
    i = rng.randrange(len(lines))
    lines.insert(i, lines[i])
    return b"\n".join(lines)


def repeat_line(rng: random.Random, data: bytes) -> bytes:
    lines = _lines(data)
    i = rng.randrange(1, len(lines)) if len(lines) > 1 else 0
    lines[i:i + 1] = [lines[i]] * rng.choice((1000, 20_000, 100_000))
    return b"\n".join(lines)


HUGE = (b"9" * 400, b"1e999", b"-1e400", str(2 ** 70).encode(), b"100000", b"-5", b"0", b"nan", b"1" * 5000)


def huge_number(rng: random.Random, data: bytes) -> bytes:
    numbers = list(re.finditer(rb"(?<![A-Za-z_])[0-9]+(?:\.[0-9]+)?", data))
    if not numbers:
        return data + rng.choice(HUGE)
    m = rng.choice(numbers)
    return data[: m.start()] + rng.choice(HUGE) + data[m.end():]


def inject_quote(rng: random.Random, data: bytes) -> bytes:
    i = rng.randrange(len(data))
    return data[:i] + rng.choice((b'"', b"'", b'""', b'"\n"', b"\\")) + data[i:]


def misspell_word(rng: random.Random, data: bytes) -> bytes:
    words = list(re.finditer(rb"[A-Za-z_]{3,}", data))
    if not words:
        return data
    m = rng.choice(words)
    w = bytearray(m.group())
    how = rng.randrange(3)
    j = rng.randrange(len(w) - 1)
    if how == 0:
        w[j], w[j + 1] = w[j + 1], w[j]      # swapped letters: OFFSTE
    elif how == 1:
        del w[-1]                             # a letter short: JOIN, End Sit
    else:
        w.insert(j, w[j])                     # a letter twice: ROOOT
    return data[: m.start()] + bytes(w) + data[m.end():]


def duplicate_key(rng: random.Random, data: bytes) -> bytes:
    """A line repeated right after itself (in YAML: the same key twice; in a CSV: a repeated row)."""
    return duplicate_line(rng, data)


def giant_field(rng: random.Random, data: bytes) -> bytes:
    i = rng.randrange(len(data))
    return data[:i] + b"x" * rng.choice((200_000, 2_000_000)) + data[i:]


def many_columns(rng: random.Random, data: bytes) -> bytes:
    lines = _lines(data)
    i = rng.randrange(len(lines))
    lines[i] = lines[i] + b",x" * rng.choice((1000, 100_000))
    return b"\n".join(lines)


MUTATIONS = {f.__name__: f for f in (byte_flip, truncate, delete_line, duplicate_line, repeat_line, huge_number,
                                     inject_quote, misspell_word, duplicate_key, giant_field, many_columns)}


# ------------------------------------------------------------------------------------------- fixtures

def make_fixtures(root: pathlib.Path) -> dict[str, tuple[pathlib.Path, list[str]]]:
    """Valid inputs of each kind: ``{kind: (file, evalsuite arguments with {file} and {out})}``."""
    import yaml

    from evalsuite.analysis.demo import sample_results_path
    from evalsuite.motion.bvh import write_bvh
    from evalsuite.motion.synthetic import synthetic_motion
    from study_app.demo import study_definition
    from study_app.samples import make_sample_stimuli

    results = root / "results.csv"
    shutil.copy(sample_results_path(), results)
    manifest = make_sample_stimuli(root / "stim", ["natural", "baseline", "system"], ["seg01", "seg02", "seg03"],
                                   seconds=1.0, attention=[("seg01", "this"), ("seg02", "70")])
    study = root / "study.yaml"
    study.write_text(yaml.safe_dump(study_definition(manifest, root), sort_keys=False))
    bvh = root / "walk.bvh"
    motion = synthetic_motion(n_joints=20, fps=30.0, seconds=2.0, seed=0)
    write_bvh(bvh, motion.skeleton, motion.values, motion.frame_time)
    return {"results": (results, ["analyze", "{file}", "-o", "{out}", "--no-figures", "--bootstrap", "100"]),
            "study": (study, ["study", "build", "{file}", "-o", "{out}/plans.json"]),
            "bvh": (bvh, ["info", "{file}"])}


# --------------------------------------------------------------------------------------------- runner

def _child(args: list[str], conn) -> None:
    import click

    from evalsuite.cli import main
    sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - the forked child exits right after
    try:
        main.main(args, standalone_mode=False)
        conn.send(("accepted", ""))
    except click.exceptions.Exit as exc:
        conn.send(("accepted" if exc.exit_code == 0 else "clean", ""))
    except click.ClickException as exc:
        conn.send(("clean", exc.format_message()))
    except BaseException as exc:   # noqa: BLE001 - what escapes is what the fuzzer reports
        conn.send(("traceback", f"{type(exc).__name__}: {str(exc)[:300]}"))
    finally:
        conn.close()


def run_one(args: list[str], timeout: float) -> tuple[str, str, float]:
    ctx = mp.get_context("fork")
    parent, child = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(args, child))
    t0 = time.perf_counter()
    proc.start()
    child.close()
    outcome, message = "hang", f"still running after {timeout:g} s"
    if parent.poll(timeout):
        try:
            outcome, message = parent.recv()
        except EOFError:
            outcome, message = "traceback", f"the process died (exit code {proc.exitcode})"
    elapsed = time.perf_counter() - t0
    if proc.is_alive():
        proc.kill()
    proc.join()
    return outcome, message, elapsed


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("-n", type=int, default=60, help="Mutated inputs per kind.")
    ap.add_argument("--seed", type=int, default=0, help="Seed of the mutations.")
    ap.add_argument("--timeout", type=float, default=10.0, help="Seconds before an input counts as a hang.")
    ap.add_argument("--slow", type=float, default=2.0, help="Seconds above which a run counts as slow.")
    ap.add_argument("--kinds", default="results,study,bvh", help="Comma-separated kinds to fuzz.")
    ap.add_argument("--show", default="traceback,hang,slow,long", help="Outcomes to list one by one.")
    opts = ap.parse_args(argv)
    # Imported once here so that every forked child starts warm.
    import evalsuite.analysis.pipeline  # noqa: F401
    import evalsuite.cli  # noqa: F401
    import evalsuite.motion.cli  # noqa: F401
    import study_app.cli  # noqa: F401
    import study_app.design  # noqa: F401

    rng = random.Random(opts.seed)
    show = set(opts.show.split(","))
    with tempfile.TemporaryDirectory(prefix="evalsuite-fuzz-") as tmp:
        root = pathlib.Path(tmp)
        fixtures = make_fixtures(root)
        for kind in opts.kinds.split(","):
            src, template = fixtures[kind]
            valid = src.read_bytes()
            counts: collections.Counter[str] = collections.Counter()
            times = []
            for i in range(opts.n):
                name = rng.choice(sorted(MUTATIONS))
                data = MUTATIONS[name](rng, valid)
                target = src.with_name(f"fuzz{src.suffix}")
                target.write_bytes(data)
                out = root / "out"
                shutil.rmtree(out, ignore_errors=True)
                out.mkdir()
                args = [a.format(file=target, out=out) for a in template]
                outcome, message, elapsed = run_one(args, opts.timeout)
                times.append(elapsed)
                counts[outcome] += 1
                flags = [outcome]
                if elapsed > opts.slow and outcome != "hang":
                    counts["slow"] += 1
                    flags.append("slow")
                if outcome == "clean" and len(message) > LONG_MESSAGE:
                    counts["long message"] += 1
                    flags.append("long")
                if show & set(flags) or "all" in show:
                    print(f"  {kind} #{i} {name}: {outcome} in {elapsed:.1f} s: {message[:200]}")
            times.sort()
            print(f"{kind}: {opts.n} inputs: " + ", ".join(f"{k} {counts[k]}" for k in
                  ("clean", "accepted", "traceback", "hang", "slow", "long message"))
                  + f"; median {times[len(times) // 2]:.2f} s, max {times[-1]:.2f} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
