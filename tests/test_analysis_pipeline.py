"""analysis.pipeline: file names made from question and scale names stay valid however long the name."""
from evalsuite.analysis.pipeline import _safe


def test_file_name_parts_stay_short_and_distinct(tmp_path):
    assert _safe("hl rating/2") == "hl_rating_2"
    long_a, long_b = "q" * 100_000, "q" * 99_999 + "r"
    assert len(_safe(long_a).encode()) <= 40
    assert _safe(long_a) != _safe(long_b)
    assert len(_safe("ä" * 100).encode()) <= 120  # 200 bytes in UTF-8: cut
    (tmp_path / f"significance_{_safe(long_a)}.csv").write_text("ok")   # the OS accepts the name
