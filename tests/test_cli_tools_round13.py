"""Round 13 of the command-line tools other than ``mmusv run`` (``study``, ``generate``, ``assets``, ``info``, ...):
what a new user's odd inputs found."""

from __future__ import annotations

from pathlib import Path

import pytest
from mmusv.cli import main
from mmusv.errors import IoError
from mmusv.world.contact_sheet import write_contact_sheet

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("overwrite", [False, True], ids=["plain", "overwrite"])
def test_a_study_names_a_folder_where_it_writes_a_file_before_the_study(
    overwrite: bool, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A folder named ``wave_study.png`` in ``-o``: with ``--overwrite`` the study ran to its end and then said
    ``cannot write .../wave_study.png: a folder ... has that name``; without it the folder was said to be 'already
    there' and to need ``--overwrite``, which then ran the study to that failure. Now refused before the study,
    either way, as a folder to remove; nothing is written."""
    out = tmp_path / "waves"
    (out / "wave_study.png").mkdir(parents=True)
    (out / "wave_study.png" / "mine.txt").write_text("mine")
    command = ["study", "waves", "--frames", "2", "-o", str(out)] + (["--overwrite"] if overwrite else [])
    assert main(command) == 2
    captured = capsys.readouterr()
    assert captured.err.strip() == (
        f"mmusv: error: -o/--output {out}: wave_study.png is a folder (or another non-file), where a file of that "
        "name is written; remove it, or give another folder"
    )
    assert captured.out == ""  # before the study: no table printed
    assert sorted(p.name for p in out.iterdir()) == ["wave_study.png"]
    assert (out / "wave_study.png" / "mine.txt").read_text() == "mine"


def test_the_contact_sheet_names_a_folder_of_its_files_names_before_rendering(tmp_path: Path) -> None:
    """``write_contact_sheet(overwrite=True)`` (``mmusv assets --render DIR --overwrite``) rendered every asset and
    then failed on a folder named ``contact_sheet.png``; now refused before the first picture."""
    (tmp_path / "contact_sheet.png").mkdir()
    with pytest.raises(IoError) as err:
        write_contact_sheet(tmp_path, names=["usv_wamv"], asset_size=(8, 6), overwrite=True)
    assert str(err.value) == (
        f"out_dir {tmp_path}: contact_sheet.png is a folder (or another non-file), where a file of that name is "
        "written; remove it, or give another folder"
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["contact_sheet.png"]  # no usv_wamv.png rendered


def test_paths_holding_brackets_are_printed_as_they_are(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The commands' consoles read what they printed as rich markup: a recording under ``[/x]`` (or ``-o "[/x]"``)
    ended ``mmusv info`` (``mmusv study``, ``generate``, ``run`` of a folder) with rich's MarkupError traceback,
    after the files were written, and a folder ``out [old]`` was said as ``out /...``. Now printed as given."""
    from mmusv.acquire import run
    from tiny_scenario import lidar_scenario

    folder = tmp_path / "[/x]" / "out [old]"
    run(lidar_scenario("tiny", frames=1), out_dir=folder)
    assert main(["info", str(folder / "tiny.mcap")]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"{folder / 'tiny.mcap'}: scenario tiny, status complete, 1 frame, agents u\n"), out
    waves = tmp_path / "[/x]" / "[red]waves"
    assert main(["study", "waves", "--frames", "2", "-o", str(waves)]) == 0
    out = capsys.readouterr().out
    said = " ".join(out.split())  # (a line past the console's width is wrapped)
    assert said.endswith(f"wrote {waves / 'wave_study.csv'} and {waves / 'wave_study.png'}"), said


def test_the_styled_lines_keep_their_words(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The lines and cells styled on purpose (the generate report's quota column, an unfinished recording's note)
    are shown with their words, not their markup."""
    from mmusv.acquire import run
    from tiny_scenario import lidar_scenario

    run(lidar_scenario("tiny", frames=1), out_dir=tmp_path / "r")
    partial = tmp_path / "tiny.mcap.partial"
    partial.write_bytes((tmp_path / "r" / "tiny.mcap").read_bytes()[:-200])
    main(["info", str(partial)])
    out = capsys.readouterr().out
    assert out.startswith("incomplete recording (.partial, no summary or damaged): counts come from reading every")
    assert "[" not in out.splitlines()[1].replace(str(tmp_path), "")
