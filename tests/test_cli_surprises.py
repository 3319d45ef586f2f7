"""What the CLI says matches what it did: progress counts, notes printed once per command."""

from __future__ import annotations

import re

import meshrepair as mr
from meshrepair.cli import main
from meshrepair.commands.common import ProgressBar
from meshrepair.io import read_mesh

from .bundled import data_path


def test_progress_bar_counts_the_pass_the_summary_reports(capsys):
    # the published noisy fandisk is solved twice by denoise (a check of the first result)
    m = read_mesh(data_path("fandisk_noisy.ply"))
    bar = ProgressBar(100, "denoise", enabled=True)
    seen = []

    def cb(entry):
        seen.append(entry)
        bar(entry)

    r = mr.denoise(m.V, m.F, callback=cb)
    assert bar.count == len(seen)
    assert bar.passes >= 2, "this input is expected to need a second solver pass"
    assert bar.bar.n == r.iterations  # the bar's last count is the summary's iterations
    assert str(len(seen)) in bar.passes_note() and str(bar.passes) in bar.passes_note()
    bar.close()


def test_progress_bar_one_pass_has_no_note():
    bar = ProgressBar(10, "x", enabled=False)
    for k in range(1, 6):
        bar({"iter": k, "rel_change": 0.1, "stage": "s"})
    assert bar.passes == 1 and bar.count == 5 and bar.passes_note() == ""


def test_denoise_summary_states_every_pass(tmp_path, capsys):
    out = tmp_path / "o.ply"
    assert main(["denoise", str(data_path("fandisk_noisy.ply")), str(out), "-q"]) == 0
    text = capsys.readouterr().out
    m = re.search(r"in (\d+) iterations .*the last of (\d+) solver passes, (\d+) iterations in "
                  r"all", text)
    assert m, text
    assert int(m.group(3)) > int(m.group(1))
