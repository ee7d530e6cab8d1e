"""bench --baseline REV (bench/compare.py): the same area at another revision in a
temporary worktree, alternating with this tree, and a CSV of per-metric ratios."""
from __future__ import annotations

import csv
import subprocess
import sys

import pytest

from voxel_addon.bench import compare


def test_ratio_is_the_median_of_the_rounds_own_ratios_with_their_spread():
    per = {"base": {"a_s": [2.0, 4.0, 1.0], "gone_s": [1.0, 1.0, 1.0]},
           "new": {"a_s": [1.0, 3.0, 1.0], "fresh_per_s": [5.0, None, 7.0]}}
    meta = {"a_s": ("s", ""), "gone_s": ("s", ""), "fresh_per_s": ("1/s", "")}
    rows = {r[0]: r for r in compare.compare(per, meta)}
    m, unit, b, n, ratio, lo, hi, spread, rounds, better, note = rows["a_s"]
    # per round 0.5, 0.75, 1.0: the median of those, not median(new) / median(base) = 0.5
    assert (b, n, ratio, lo, hi, rounds, better) == (2.0, 1.0, 0.75, 0.5, 1.0, 3, "lower")
    assert spread == pytest.approx(100 * 0.25 / 0.75)
    assert rows["fresh_per_s"][2] is None and rows["fresh_per_s"][3] == 6.0
    assert rows["fresh_per_s"][4] is None and rows["fresh_per_s"][9] == "higher"
    assert rows["fresh_per_s"][10].startswith("new metric")
    assert rows["gone_s"][3] is None and rows["gone_s"][10].startswith("gone")


def test_baseline_head_on_the_quick_storage_area(tmp_path):
    out = tmp_path / "out"
    r = subprocess.run([sys.executable, "-m", "voxel_addon", "bench", "--out", str(out),
                        "--area", "storage", "--quick", "--baseline", "HEAD", "--rounds", "1"],
                       cwd=compare.ROOT, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr[-2000:]
    with (out / "bench.csv").open(newline="") as f:
        rows = {row["metric"]: row for row in csv.DictReader(f)}
    assert "HEAD" in rows.pop("baseline")["note"]
    assert {"load_chunks_per_s", "bytes_per_chunk_disk", "codec_zstd_decode_us"} <= set(rows)
    for m, row in rows.items():
        assert row["rounds"] == "1" and row["base"] and row["new"], m
    # the same code on the same seed: sizes are equal, times near
    assert float(rows["bytes_per_chunk_disk"]["ratio"]) == 1.0
    assert 0.2 < float(rows["load_chunks_per_s"]["ratio"]) < 5
    assert rows["load_chunks_per_s"]["better"] == "higher"
    assert (out / "baseline.png").exists()
    # the temporary worktree is gone again
    wt = subprocess.run(["git", "worktree", "list"], cwd=compare.ROOT, capture_output=True,
                        text=True).stdout
    assert "voxel-baseline-" not in wt


def test_an_unknown_revision_is_one_line(tmp_path):
    r = subprocess.run([sys.executable, "-m", "voxel_addon", "bench", "--out", str(tmp_path),
                        "--baseline", "no-such-rev-xyz", "--quick"],
                       cwd=compare.ROOT, capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
