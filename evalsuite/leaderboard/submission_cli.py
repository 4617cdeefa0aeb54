"""``evalsuite validate-submission DIR --against GT_DIR``: the report of
:func:`evalsuite.leaderboard.submission.validate_submission` as text or JSON; exit status 1 on any error."""
from __future__ import annotations

import json
import pathlib

import click

from evalsuite.leaderboard.submission import (
    DEFAULT_LENGTH_TOLERANCE,
    LEADERBOARD_LENGTH_TOLERANCE,
    SubmissionReport,
    validate_submission,
)

__all__ = ["validate_submission_command", "report_text"]


def report_text(report: SubmissionReport) -> str:
    """The report for a participant: a summary, then each file's problems with what was expected."""
    tol = report.tolerances
    lines = [f"submission: {report.submission}", f"against:    {report.against}",
             f"files:      {report.files} for {report.recordings} recordings; samples per recording: "
             + (", ".join(f"{n} x{c}" for n, c in sorted(_count(report).items())) or "none"),
             f"lengths:    an error beyond {100 * tol['length_error_share']:g} % of the ground truth's frames (at "
             f"least {tol['length_error_min_frames']}); the organisers' script warns beyond "
             f"{100 * tol['leaderboard_warning_share']:g} % and scores the shorter length"]
    current = None
    for p in report.problems:
        if p.file != current:
            lines.append(f"\n{p.file}")
            current = p.file
        lines.append(f"  {p.severity.upper()} [{p.code}] {p.message}")
        lines.append(f"      expected: {p.expected}")
    verdict = "OK: no errors" if report.ok else f"NOT READY: {len(report.errors)} errors"
    lines.append(f"\n{verdict}, {len(report.warnings)} warnings")
    return "\n".join(lines)


def _count(report: SubmissionReport) -> dict[int, int]:
    out: dict[int, int] = {}
    for n in report.samples.values():
        out[n] = out.get(n, 0) + 1
    return out


@click.command("validate-submission")
@click.argument("directory", type=click.Path(file_okay=False, path_type=pathlib.Path))
@click.option("--against", "against", required=True, type=click.Path(file_okay=False, path_type=pathlib.Path),
              help="The ground truth: a folder of <video_id>.npz (the test set), or a BEAT2 language folder "
                   "(smplxflame_30/ + train_test_split.csv: its test split).")
@click.option("--length-tolerance", type=click.FloatRange(min=0), default=DEFAULT_LENGTH_TOLERANCE,
              show_default=True, help="Largest frame-count difference from the ground truth that is not an error, "
              f"as a share of its frames (at least 1 frame); beyond {LEADERBOARD_LENGTH_TOLERANCE:g} the organisers' "
              "script warns too.")
@click.option("--json", "as_json", is_flag=True, help="Print the report as JSON (problems with file, severity, "
              "code, message, expected).")
@click.option("--progress/--no-progress", default=True, show_default=True,
              help="A progress bar over the files (on stderr).")
def validate_submission_command(directory: pathlib.Path, against: pathlib.Path, length_tolerance: float,
                                as_json: bool, progress: bool) -> None:
    """Check a GENEA Leaderboard submission (SMPL-X <video_id>_<k>.npz files) against the ground truth: names,
    samples per recording, keys, shapes, dtypes, frame rate, NaN/Inf, unreadable files and lengths.

    Exit status 1 when there is any error; warnings alone exit 0.

    \b
    Examples:
      evalsuite validate-submission my_system/ --against BEAT2/beat_english_v2.0.0
      evalsuite validate-submission my_system/ --against test_gt/ --json > report.json
    """
    report = validate_submission(directory, against, length_tolerance=length_tolerance,
                                 progress=progress and not as_json)
    click.echo(json.dumps(report.as_dict(), indent=1) if as_json else report_text(report))
    if not report.ok:
        raise SystemExit(1)
