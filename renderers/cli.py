"""``evalsuite render``: comparison videos, stills, study stimuli and attention checks."""
from __future__ import annotations

import functools
import pathlib
import warnings

import click

from evalsuite.errors import InputError
from evalsuite.motion.smplx_option import smplx_model_option
from renderers.styles import STYLES


def _settings_options(fn):
    """Options shared by every rendering command."""
    options = [
        click.option("--width", type=int, default=640, show_default=True, help="Width of one panel in pixels."),
        click.option("--height", type=int, default=480, show_default=True, help="Height of one panel in pixels."),
        click.option("--view", type=click.Choice(["front", "three-quarter", "side"]), default="front",
                     show_default=True, help="Camera preset; framed automatically from the motion."),
        click.option("--style", "body", type=click.Choice(STYLES.names()), default="stick", show_default=True,
                     help="Body style: stick figure, mannequin (a neutral body for any skeleton), character (a "
                          "skinned glTF character, see --character) or an installed plug-in's."),
        click.option("--character", type=click.Path(exists=True, dir_okay=False), default=None,
                     help="glTF 2.0 character file (.glb/.gltf with a skin) for --style character."),
        click.option("--framing", type=click.Choice(["full", "above-knees", "upper"]), default="full",
                     show_default=True,
                     help="Frame the full body, down to the knees (the GENEA Leaderboard's cut, hides foot "
                          "sliding), or the upper body."),
        click.option("--face", type=click.Choice(["visible", "blank"]), default="visible", show_default=True,
                     help="visible: the head shows where it faces (nose and visor); blank: a plain head, a face "
                          "mask as the GENEA Leaderboard uses (the stick figure has no face either way)."),
        click.option("--fps", type=float, default=None,
                     help="Video frame rate; the motion is resampled to it (default: the motion's own)."),
        click.option("--up", "up_axis", type=click.Choice(["y", "z"]), default="y", show_default=True,
                     help="The motion's up axis."),
        click.option("--msaa", type=click.Choice(["0", "2", "4", "8"]), default="4", show_default=True,
                     help="Multisample anti-aliasing samples (0: jagged edges, about 10% faster)."),
        click.option("--floor/--no-floor", default=None,
                     help="Draw a floor plane (default: when the body style stands on one, as the mannequin does, "
                          "with a soft contact shadow)."),
        click.option("--shadow/--no-shadow", default=False, show_default=True,
                     help="Cast the figure's shadow on the floor (implies --floor; slower)."),
        click.option("--head/--no-head", default=True, show_default=True, help="Draw a head marker."),
        click.option("--center/--no-center", default=True, show_default=True,
                     help="Move each clip's mean root position to the origin so clips line up."),
        click.option("--crf", type=int, default=20, show_default=True, help="H.264 quality (lower = better)."),
        click.option("--start", type=float, default=None,
                     help="Start time in seconds; the speech audio is cut with the motion."),
        click.option("--end", type=float, default=None,
                     help="End time in seconds; the speech audio is cut with the motion."),
        click.option("--drop-joints", default="", metavar="NAMES",
                     help="Comma-separated joints not to draw nor frame, besides the non-body joints "
                          "(world root at the floor, zero-length helpers) that are always left out."),
    ]
    for opt in reversed(options):
        fn = opt(fn)
    return smplx_model_option(fn)   # SMPL-X motion is drawn from joint positions, which need the model file


def _settings(kw):
    from renderers.figure import FigureStyle
    from renderers.scene import RenderSettings

    shadow = kw.pop("shadow")
    floor = kw.pop("floor")
    style = FigureStyle(floor=True if shadow else floor, shadow=shadow, head_marker=kw.pop("head"))
    return RenderSettings(width=kw.pop("width"), height=kw.pop("height"), view=kw.pop("view"),
                          framing=kw.pop("framing"), fps=kw.pop("fps"), up_axis=kw.pop("up_axis"),
                          msaa=int(kw.pop("msaa")), crf=kw.pop("crf"), center=kw.pop("center"),
                          style=style, drop_joints=kw.pop("drop_joints"), body=kw.pop("body"),
                          character=kw.pop("character"), face=kw.pop("face"))


def _echo_warnings(fn):
    """Show our warnings (audio/motion length mismatch) as one 'Warning:' line each."""
    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", UserWarning)
            try:
                return fn(*args, **kwargs)
            finally:
                for w in caught:
                    click.echo(f"Warning: {w.message}", err=True)
    return wrapper


def _captions(captions, paths):
    if captions is None:
        return [pathlib.Path(p).stem for p in paths]
    if captions == "":
        return None
    parts = [c.strip() for c in captions.split(",")]
    if len(parts) != len(paths):
        raise InputError(f"{len(parts)} captions for {len(paths)} motions; expected one per motion",
                         field="--captions")
    return parts


@click.group()
def render():
    """Render motion as videos offscreen (no display or GPU needed): stick figure, mannequin or character.

    Videos are H.264 MP4 with the speech audio muxed in sync: a cut (--start/--end) cuts
    the audio with the motion. Conditions shown together share one camera, framed
    automatically from their motion.
    """


@render.command()
@click.argument("motions", nargs=-1, required=True, type=click.Path(exists=True, dir_okay=False))
@click.option("--audio", type=click.Path(exists=True, dir_okay=False), help="Speech audio (WAV, or any format ffmpeg reads).")
@click.option("-o", "--out", required=True, type=click.Path(dir_okay=False, path_type=pathlib.Path), help="Output .mp4.")
@click.option("--captions", default=None,
              help="Comma-separated caption per motion (default: file names; '' for none).")
@click.option("--layout", type=click.Choice(["side", "grid"]), default="side", show_default=True,
              help="One row, or a near-square grid.")
@click.option("--cols", type=int, default=None, help="Number of columns (overrides --layout).")
@_settings_options
@_echo_warnings
def compare(motions, audio, out, captions, layout, cols, start, end, **kw):
    """Side-by-side (or grid) video of several motions of one segment.

    \b
    Example:
      evalsuite render compare natural.bvh A.bvh B.bvh --audio speech.wav -o out.mp4
    """
    from renderers.render import prepare_motions, render_video

    settings = _settings(kw)
    ms = prepare_motions(motions, settings, start, end)
    info = render_video(ms, out, settings, audio=audio, captions=_captions(captions, motions), layout=layout,
                        cols=cols, progress=True)
    click.echo(f"Wrote {out} ({info['width']}x{info['height']}, {info['n_frames']} frames at "
               f"{info['fps']:g} fps, {info['duration']:.2f} s)")


@render.command()
@click.argument("motion", type=click.Path(exists=True, dir_okay=False))
@click.option("--audio", type=click.Path(exists=True, dir_okay=False), help="Speech audio.")
@click.option("-o", "--out", required=True, type=click.Path(dir_okay=False, path_type=pathlib.Path), help="Output .mp4.")
@click.option("--caption", default=None, help="Caption above the figure.")
@_settings_options
@_echo_warnings
def video(motion, audio, out, caption, start, end, **kw):
    """Video of a single motion."""
    from renderers.render import prepare_motions, render_video

    settings = _settings(kw)
    ms = prepare_motions([motion], settings, start, end)
    info = render_video(ms, out, settings, audio=audio, captions=[caption] if caption else None, progress=True)
    click.echo(f"Wrote {out} ({info['width']}x{info['height']}, {info['n_frames']} frames at "
               f"{info['fps']:g} fps, {info['duration']:.2f} s)")


@render.command()
@click.argument("motions", nargs=-1, required=True, type=click.Path(exists=True, dir_okay=False))
@click.option("-o", "--out", required=True, type=click.Path(dir_okay=False, path_type=pathlib.Path), help="Output .png.")
@click.option("--frame", type=int, default=None,
              help="Frame index counted from the first frame of the cut (default 0).")
@click.option("--time", "time_s", type=float, default=None,
              help="Time in seconds on the motion file's own clock, as --start/--end (instead of --frame).")
@click.option("--captions", default="", help="Comma-separated caption per motion (default: none).")
@click.option("--layout", type=click.Choice(["side", "grid"]), default="side", show_default=True,
              help="One row, or a near-square grid.")
@click.option("--cols", type=int, default=None, help="Number of columns (overrides --layout).")
@_settings_options
def still(motions, out, frame, time_s, captions, layout, cols, start, end, **kw):
    """PNG of one frame of one or more motions (side by side, shared camera)."""
    from renderers.render import prepare_motions, render_still

    settings = _settings(kw)
    ms = prepare_motions(motions, settings, start, end)
    if frame is not None and time_s is not None:
        raise InputError("give --frame or --time, not both")
    index = frame or 0
    if time_s is not None:   # the file's clock, like --start: frame round(t * fps) of the file
        index = int(round(time_s * ms[0].fps)) - int(round(ms.start * ms[0].fps))
        if index < 0:
            raise InputError(f"--time {time_s:g} s is before the cut's start ({ms.start:g} s)", field="--time")
    render_still(ms, out, settings, frame=index, captions=_captions(captions, motions), layout=layout, cols=cols)
    click.echo(f"Wrote {out}")


@render.command()
@click.argument("config", type=click.Path(exists=True, dir_okay=False))
@click.option("-j", "--jobs", type=int, default=1, show_default=True, help="Local worker processes.")
@click.option("--dask", "dask_address", default=None, metavar="ADDRESS",
              help="Scheduler address of an existing dask.distributed cluster (e.g. tcp://host:8786).")
@click.option("--force", is_flag=True, help="Re-render even videos that are up to date.")
@click.option("--equal-size", type=click.Choice(["off", "pad", "cbr"]), default=None,
              help="Make the videos of each segment equally large, so a file's size tells nothing: pad them with a "
                   "box players ignore, or encode at a constant bitrate and pad the rest (default: the config's "
                   "equal_size, else off).")
@click.option("--bitrate", default=None, metavar="RATE",
              help="Bitrate of --equal-size cbr, e.g. 400k (default: the config's bitrate, else 400k).")
@click.option("--mute/--no-mute", default=None,
              help="Videos without sound even where segments have audio, as realism studies use (default: the "
                   "config's mute, else sound).")
def stimuli(config, jobs, dask_address, force, equal_size, bitrate, mute):
    """Render every condition x segment of CONFIG, plus attention checks, with blinded names.

    Writes the videos and a private manifest.csv (file -> condition, segment, kind,
    expected answer, sha256) to the config's output folder; videos whose inputs and
    settings did not change since the last run are skipped. See docs/render.md.
    """
    from renderers.stimuli import build_stimuli
    from renderers.stimuli_config import BITRATE_RE

    if jobs < 1:
        raise InputError("--jobs must be at least 1")
    if bitrate is not None and not BITRATE_RE.match(bitrate):
        raise InputError(f"expected a bitrate such as 400k or 1.5M, got {bitrate!r}", field="--bitrate")
    result = build_stimuli(config, jobs=jobs, dask_address=dask_address, force=force, echo=click.echo,
                           equal_size=equal_size, bitrate=bitrate, mute=mute)
    click.echo(f"{result['rendered']} rendered, {result['skipped']} up to date; manifest: {result['manifest']}")


@render.command()
@click.argument("src", type=click.Path(exists=True, dir_okay=False))
@click.option("-o", "--out", required=True, type=click.Path(dir_okay=False, path_type=pathlib.Path))
@click.option("--check", type=click.Choice(["distorted_audio", "distorted_video", "instruction"]), required=True,
              help="Kind of attention check.")
@click.option("--text", default=None, help="Instruction text (instruction checks).")
@click.option("--appear", "appear_s", type=float, default=3.0, show_default=True,
              help="Seconds before the instruction appears.")
@click.option("--seed", type=int, default=0, show_default=True)
def attention(src, out, check, text, appear_s, seed):
    """Make an attention-check video from any stimulus video SRC."""
    from renderers.attention import make_attention_check

    info = make_attention_check(src, out, check, text=text, appear_s=appear_s, seed=seed)
    click.echo(f"Wrote {out} ({info['n_frames']} frames)")
