"""A conversion that converts nothing says why: the error named the recording ("no complete frame in X") but not
the damage, cut or missing topics that its skipped frames' reasons give (those go with the report, which is not
written then), so ``mmusv convert`` of a recording whose one chunk is damaged said nothing ``mmusv info`` says."""

from __future__ import annotations

from pathlib import Path

import pytest
from mmusv.errors import IoError
from mmusv.export import convert


def test_a_damaged_recording_says_the_damage(coop_rec: Path, tmp_path: Path) -> None:
    data = bytearray(coop_rec.read_bytes())
    data[len(data) // 2] ^= 0xFF  # inside the recording's chunk (every frame is in it): its CRC no longer matches
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(data))
    with pytest.raises(IoError) as caught:
        convert(bad, to="coco", out_dir=tmp_path / "o", splits=None)
    msg = str(caught.value)
    assert msg.startswith(f"nothing converted: no complete frame in {bad}; nothing written ("), msg
    assert f"{bad}: frames 0..2 lost from the recording" in msg, msg
    # the flipped byte fails the chunk's CRC or its zstd stream, depending on where it falls
    assert "damaged chunk, skipped: " in msg and ("CRC mismatch" in msg or "does not decompress" in msg), msg
    assert not (tmp_path / "o").exists()
