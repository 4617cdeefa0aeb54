"""Speed of the published Aud2Repr2Pose demo model (``aud2repr2pose-demo``, issue 14: at least 50x real time).

Generates the demo's own 20-second recording through the plug-in runner (features with Praat prosody, the
speech encoder, the decoder, smoothing, the motion file) ``--runs`` times after one warm-up run, and prints the
median time and the speed as seconds of speech per second of computing, with the load average (other
processes slow every figure down). The model folder is the demo repository's ``models/`` (for this project's
checks: ``../shared/weights/aud2repr2pose-demo``, which is never committed).

Usage: python benchmarks/bench_demo_model.py [--model DIR] [--audio WAV] [--runs 7]
"""
from __future__ import annotations

import argparse
import os
import pathlib
import statistics
import sys
import tempfile
import time

HERE = pathlib.Path(__file__).resolve().parent
DEFAULT_MODEL = HERE.parent.parent / "shared" / "weights" / "aud2repr2pose-demo"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", type=pathlib.Path, default=DEFAULT_MODEL)
    ap.add_argument("--audio", type=pathlib.Path, default=None, help="default: MODEL/audio/audio3_20sec.wav")
    ap.add_argument("--runs", type=int, default=7)
    args = ap.parse_args(argv)
    audio = args.audio or args.model / "audio" / "audio3_20sec.wav"
    if not audio.is_file():
        print(f"no demo model/recording at {args.model} (give --model DIR --audio WAV)")
        return 2
    from evalsuite.audio import read_wav
    from evalsuite.generators import find_generator
    from evalsuite.generators.requests import request_for_audio
    from evalsuite.generators.runner import generate

    x, rate = read_wav(audio)
    duration = len(x) / rate
    entry = find_generator("aud2repr2pose-demo")
    req = request_for_audio(audio, 20.0)
    times = []
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(args.runs + 1):
            t0 = time.perf_counter()
            generate(entry, [req], pathlib.Path(tmp) / str(i), model_dir=args.model, progress=False,
                     check_determinism=False)
            if i:                                   # the first run loads libraries and the model files
                times.append(time.perf_counter() - t0)
    med = statistics.median(times)
    print(f"{duration:.1f} s of speech: median {med:.3f} s over {len(times)} runs (min {min(times):.3f} s) -> "
          f"{duration / med:.1f}x real time (best {duration / min(times):.1f}x); target >= 50x; "
          f"load average {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
