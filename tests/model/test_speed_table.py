"""speed_table.c, the reader of a measured input-shaft speed table (engine.speed_table): a bad
table is refused naming the table, the row and what is allowed; a missing one names the
parameter.  (The readers' corpus -- line ends, quoting, sizes, FIFOs -- is read through
the FMUs of both flavours in tests/adversarial/test_readers.py.)"""

import pytest

from drive_rattle import DrivelineParameters, ModelError


@pytest.mark.parametrize("content, fragment", [
    ("0,1\n0,2\n", "row 2: time 0 s does not increase"),
    ("0,1\n", "needs at least two rows"),
    ("", "needs at least two rows"),
    ("0,1\n1,x\n", "row 2: expected two numbers"),
    ("0,1\n1,nan\n", "row 2: speed 'nan' reads as nan; allowed: finite numbers"),
])
def test_bad_speed_tables_are_refused_naming_the_table_and_row(tmp_path, monkeypatch, content,
                                                               fragment):
    # A relative path: the message quotes at most 80 bytes of it, and pytest's own folder
    # for tmp_path is of any length (test_a_long_path_is_quoted_to_80_bytes_and_its_length: longer).
    monkeypatch.chdir(tmp_path)
    (tmp_path / "bad.csv").write_text(content)
    with pytest.raises(ModelError) as err:
        DrivelineParameters(speed_table="bad.csv")
    assert fragment in str(err.value) and "speed table 'bad.csv'" in str(err.value)


def test_a_missing_speed_table_names_the_parameter(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ModelError, match=r"'engine\.speed_table' = 'nope\.csv' cannot be read: "
                                         r"no such file or directory; allowed: a readable regular "
                                         r"file of at most \d+ bytes"):
        DrivelineParameters(speed_table="nope.csv")


def test_a_long_path_is_quoted_to_80_bytes_and_its_length(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    path = "d" * 100 + "/nope.csv"
    with pytest.raises(ModelError) as err:
        DrivelineParameters(speed_table=path)
    assert f"'engine.speed_table' = '{path[:80]}'... ({len(path)} bytes) cannot be read" \
        in str(err.value)
