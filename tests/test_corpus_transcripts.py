"""Transcript formats: round trips, the formats' real conventions, and precise errors."""
from __future__ import annotations

import json

import numpy as np
import pytest
from corpus_helpers import wav

from evalsuite.corpus.transcripts import (
    count_syllables,
    estimate_timings,
    read_transcript,
    textgrid_tiers,
    voiced_span,
    write_transcript,
)
from evalsuite.corpus.types import Transcript, Word
from evalsuite.errors import InputError

WORDS = Transcript((Word("deep", 0.4, 0.8), Word("learning", 0.8, 1.25), Word('"quoted" word', 2.0, 3.123456),
                    Word("ünïcode", 6.0, 6.5)))


@pytest.mark.parametrize("suffix", [".json", ".tsv", ".TextGrid"])
def test_round_trip_keeps_words_and_times(tmp_path, suffix):
    path = tmp_path / f"t{suffix}"
    write_transcript(WORDS, path)
    back = read_transcript(path)
    assert [w.text for w in back.words] == [w.text for w in WORDS.words]
    np.testing.assert_allclose([(w.start, w.end) for w in back.words], [(w.start, w.end) for w in WORDS.words],
                               atol=1e-6)
    assert not back.estimated


def test_round_trip_of_plain_text_gives_the_same_words_and_the_same_estimate(tmp_path):
    audio = wav(tmp_path / "t.wav", 3.0, voiced=(0.5, 2.5))
    first = read_transcript(_write(tmp_path / "t.txt", "Deep learning is everything.\n"))
    write_transcript(first, tmp_path / "u.txt")
    second = read_transcript(tmp_path / "u.txt", audio=audio)
    assert second.words == first.words


def test_google_json_as_gesticulator_writes_it_with_s_suffix_times(tmp_path):
    data = [{"alternatives": [{"transcript": "deep learning", "confidence": 0.9,
                               "words": [{"start_time": "0s", "end_time": "0.400s", "word": "deep"},
                                         {"start_time": "0.400s", "end_time": "6s", "word": "learning"}]}]},
            {"alternatives": [{"transcript": "is", "words": [{"startTime": "6.1s", "endTime": "6.5s", "word": "is"}]}]},
            {"alternatives": [{"words": [{"startOffset": "7s", "endOffset": {"seconds": 7, "nanos": 500000000},
                                          "word": "fun."}]}]}]
    path = _write(tmp_path / "g.json", json.dumps(data))
    t = read_transcript(path)
    assert [(w.text, w.start, w.end) for w in t.words] == [("deep", 0.0, 0.4), ("learning", 0.4, 6.0),
                                                          ("is", 6.1, 6.5), ("fun.", 7.0, 7.5)]
    write_transcript(t, tmp_path / "out.json")
    written = json.loads((tmp_path / "out.json").read_text())
    assert written[0]["alternatives"][0]["words"][1] == {"start_time": "0.4s", "end_time": "6s", "word": "learning"}


def test_google_json_object_with_results_key(tmp_path):
    path = _write(tmp_path / "g.json", json.dumps({"results": [{"alternatives": [
        {"words": [{"startTime": "1.5s", "endTime": "2s", "word": "hi"}]}]}]}))
    assert read_transcript(path).words == (Word("hi", 1.5, 2.0),)


def test_genea_tsv_has_no_header_and_keeps_multi_word_annotations(tmp_path):
    path = _write(tmp_path / "a.tsv", "0.0\t0.39\tSo\n0.39\t1.2\tyou know,\n\n1.5\t1.75\tright?\n")
    t = read_transcript(path)
    assert [(w.text, w.start, w.end) for w in t.words] == [("So", 0.0, 0.39), ("you know,", 0.39, 1.2),
                                                          ("right?", 1.5, 1.75)]
    assert read_transcript(_write(tmp_path / "h.tsv", "start\tend\tword\n0\t1\thi\n")).words == (Word("hi", 0, 1),)


def test_empty_tsv_is_an_error_unless_allowed(tmp_path):
    path = _write(tmp_path / "empty.tsv", "")
    with pytest.raises(InputError, match=r"empty\.tsv: the file is empty; expected a GENEA TSV transcript"):
        read_transcript(path)
    assert len(read_transcript(path, allow_empty=True)) == 0


SHORT_TEXTGRID = '''File type = "ooTextFile"
Object class = "TextGrid"

0
2.5
<exists>
2
"IntervalTier"
"phones"
0
2.5
1
0
2.5
"d iy p"
"IntervalTier"
"words"
0
2.5
3
0
0.5
""
0.5
1.0
"deep"
1.0
2.5
"learning"
'''


def test_textgrid_short_format_and_tier_choice(tmp_path):
    path = _write(tmp_path / "s.TextGrid", SHORT_TEXTGRID)
    assert textgrid_tiers(path) == [("phones", "IntervalTier"), ("words", "IntervalTier")]
    assert read_transcript(path).words == (Word("deep", 0.5, 1.0), Word("learning", 1.0, 2.5))
    assert read_transcript(path, tier="phones").words == (Word("d iy p", 0.0, 2.5),)
    with pytest.raises(InputError, match=r"s\.TextGrid: tier: no interval tier named 'syllables'; the file's tiers: "
                                         r"'phones', 'words'"):
        read_transcript(path, tier="syllables")


def test_textgrid_long_format_in_utf16_as_praat_writes_non_ascii(tmp_path):
    write_transcript(WORDS, tmp_path / "a.TextGrid")
    text = (tmp_path / "a.TextGrid").read_text(encoding="utf-8")
    (tmp_path / "b.TextGrid").write_bytes(text.encode("utf-16"))
    assert read_transcript(tmp_path / "b.TextGrid").words == read_transcript(tmp_path / "a.TextGrid").words


def test_plain_text_spreads_words_over_the_voiced_span_by_syllables(tmp_path):
    audio = wav(tmp_path / "p.wav", 4.0, voiced=(1.0, 3.0))
    assert voiced_span(*_read(audio)) == pytest.approx((1.0, 3.0), abs=0.021)
    t = read_transcript(_write(tmp_path / "p.txt", "Deep learning is everything."), audio=audio)
    syl = [count_syllables(w) for w in ("Deep", "learning", "is", "everything.")]
    assert syl == [1, 2, 1, 4]
    assert t.estimated and all(w.estimated for w in t.words)
    durations = np.array([w.duration for w in t.words])
    np.testing.assert_allclose(durations / durations.sum(), np.array(syl) / sum(syl), atol=1e-9)
    assert t.words[0].start == pytest.approx(1.0, abs=0.021) and t.words[-1].end == pytest.approx(3.0, abs=0.021)


def test_plain_text_finds_the_audio_beside_it_or_says_it_needs_one(tmp_path):
    path = _write(tmp_path / "q.txt", "hello there")
    with pytest.raises(InputError, match=r"q\.txt: a plain-text transcript has no times; give the audio"):
        read_transcript(path)
    wav(tmp_path / "q.wav", 2.0)
    assert read_transcript(path).words[-1].end == pytest.approx(2.0, abs=0.021)
    assert estimate_timings(["a", "b"], 0.0, 1.0).words == (Word("a", 0, 0.5, True), Word("b", 0.5, 1.0, True))


@pytest.mark.parametrize("name, content, pattern", [
    ("bad_time.tsv", "0.0\t0.5\tyes\n0.5\tlater\tno\n",
     r"bad_time\.tsv:2: end \(field 2\): expected a time in seconds such as 1\.25, found 'later'"),
    ("nan.tsv", "nan\t0.5\tyes\n", r"nan\.tsv:1: start \(field 1\): expected a time in seconds"),
    ("backwards.tsv", "0.0\t0.5\tyes\n0.9\t0.6\tno\n",
     r"backwards\.tsv:2: word 'no' ends \(0\.6 s\) before it starts \(0\.9 s\); expected start <= end"),
    ("overlap.tsv", "0.0\t0.5\tyes\n0.4\t0.6\tno\n",
     r"overlap\.tsv:2: word 'no' starts at 0\.4 s, before 'yes' \(line 1\) ends at 0\.5 s; expected words in "
     r"time order without overlap"),
    ("fields.tsv", "0.0\t0.5\n", r"fields\.tsv:1: expected 3 tab-separated fields \(start, end, word\), found 2"),
    ("bad_time.json", '[{"alternatives": [{"words": [{"start_time": "0.4", "end_time": "1s", "word": "a"}]}]}]',
     r"bad_time\.json:1: results\[0\]\.alternatives\[0\]\.words\[0\]\.start_time: expected a duration string such as "
     r"\"0\.400s\""),
    ("missing.json", '[{"alternatives": [{"words": [{"start_time": "0.4s", "word": "a"}]}]}]',
     r"missing\.json:1: results\[0\]\.alternatives\[0\]\.words\[0\]: missing 'end_time'"),
    ("syntax.json", '[{"alternatives": [\n  {"words": ]}]', r"syntax\.json:2: column 13: not valid JSON \(Expecting value\); expected Google speech-to-text JSON"),
    ("overlap.json", '[{"alternatives": [{"words": [{"start_time": "0s", "end_time": "1s", "word": "a"},'
                     '{"start_time": "0.5s", "end_time": "2s", "word": "b"}]}]}]',
     r"overlap\.json:1: results\[0\]\.alternatives\[0\]\.words\[1\]: word 'b' starts at 0\.5 s, before 'a'"),
    ("empty.json", "  \n", r"empty\.json: the file is empty; expected a Google speech-to-text JSON file"),
    ("bad.TextGrid", SHORT_TEXTGRID.replace('"deep"', "deep"),
     r"bad\.TextGrid:26: found unquoted text 'deep'; expected a quoted string or a number"),
    ("short.TextGrid", SHORT_TEXTGRID[:-12], r"short\.TextGrid:\d+: the file ends early; expected text of interval 3"),
    ("open.TextGrid", SHORT_TEXTGRID.replace('"learning"', '"learning'),
     r"open\.TextGrid:29: a string is opened with \" but never closed"),
    ("header.TextGrid", "hello", r"header\.TextGrid:1: found unquoted text 'hello'; expected a quoted string"),
    ("sound.TextGrid", 'File type = "ooTextFile"\nObject class = "Sound"\n',
     r"sound\.TextGrid:2: expected Object class = \"TextGrid\""),
])
def test_malformed_transcripts_name_file_line_and_what_was_expected(tmp_path, name, content, pattern):
    path = _write(tmp_path / name, content)
    with pytest.raises(InputError, match=pattern):
        read_transcript(path)


def test_invalid_utf8_names_line_and_column(tmp_path):
    path = tmp_path / "latin1.tsv"
    path.write_bytes("0\t1\tyes\n1\t2\tcaf\xe9\n".encode("latin-1"))
    with pytest.raises(InputError, match=r"latin1\.tsv:2: column 8: byte 0xe9 is not valid UTF-8; expected a UTF-8 "
                                         r"GENEA TSV transcript file"):
        read_transcript(path)


def test_unknown_suffix_and_format_name(tmp_path):
    with pytest.raises(InputError, match=r"cannot tell the transcript format from the suffix '\.srt'"):
        read_transcript(tmp_path / "a.srt")
    with pytest.raises(InputError, match=r"format: unknown transcript format 'srt'"):
        read_transcript(tmp_path / "a.txt", format="srt")
    write_transcript(WORDS, tmp_path / "named.dat", format="tsv")
    assert len(read_transcript(tmp_path / "named.dat", format="genea_tsv")) == 4


def _write(path, text):
    path.write_text(text, encoding="utf-8")
    return path


def _read(path):
    from evalsuite.audio import read_wav
    return read_wav(path)


def test_json_errors_name_the_line_of_the_word(tmp_path):
    data = [{"alternatives": [{"words": [{"start_time": "0s", "end_time": "1s", "word": "a"},
                                         {"start_time": "1s", "end_time": "1.5", "word": "b"}]}]}]
    path = _write(tmp_path / "pretty.json", json.dumps(data, indent=2))
    with pytest.raises(InputError, match=r"pretty\.json:11: results\[0\]\.alternatives\[0\]\.words\[1\]\.end_time: "
                                         r"expected a duration string such as \"0\.400s\" or \"6s\", found '1\.5'"):
        read_transcript(path)
