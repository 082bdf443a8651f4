"""A study file that is not text or not JSON is refused in rodval's words (the fuzz rerun at
500 examples of ``test_fuzz_outputs.py`` found `rodval report` quoting Python's codec error:
"unreadable (UnicodeDecodeError: 'utf-8' codec can't decode byte 0x85 ...)")."""

import pytest

from rodval.cli import main


@pytest.mark.parametrize(
    "content, words",
    [
        (b"\x85\x00{", "not UTF-8 text: byte 0x85 at position 0"),
        (b'{"rodval": ', "not JSON: Expecting value at line 1, column 12"),
    ],
)
def test_report_of_a_damaged_study_json_says_what_is_wrong(tmp_path, capsys, content, words):
    folder = tmp_path / "mine"
    folder.mkdir()
    (folder / "study.json").write_bytes(content)
    assert main(["report", str(folder)]) == 2
    err = capsys.readouterr().err
    assert words in err
    assert "codec" not in err and "Error" not in err, err
