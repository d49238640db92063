"""Motion records and scatter tables as spreadsheets save them (issue 43, item 14): "CSV UTF-8"
starts with a byte-order mark and ends its lines with CRLF; old Mac exports end them with CR. The
values read are the same as from plain text, and `check` accepts the scene on the command line."""
import os

import pytest

from jaxslosh.campaign.cases import read_scatter
from jaxslosh.cli.main import main
from jaxslosh.scene.record import read_record

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ROWS = "t,sway,roll\n0,0,0\n1,0.01,0.002\n2,0,0\n3,-0.01,-0.002\n4,0,0\n"


@pytest.mark.parametrize("bom, eol", [(b"\xef\xbb\xbf", b"\r\n"), (b"\xef\xbb\xbf", b"\n"), (b"", b"\r\n"),
                                      (b"\xef\xbb\xbf", b"\r")])
def test_a_spreadsheet_record_reads_as_the_plain_one(tmp_path, bom, eol):
    plain = tmp_path / "plain.csv"
    plain.write_bytes(ROWS.encode())
    sheet = tmp_path / "sheet.csv"
    sheet.write_bytes(bom + ROWS.encode().replace(b"\n", eol))
    want = read_record(str(plain), "vessel.forced.file", "plain.csv")
    got = read_record(str(sheet), "vessel.forced.file", "sheet.csv")
    assert got == want
    assert got[0] == (0.0, 1.0, 2.0, 3.0, 4.0) and [c for c, _ in got[1]] == ["sway", "roll"]


def test_check_accepts_a_csv_utf8_record(tmp_path, capsys):
    (tmp_path / "motion.csv").write_bytes(b"\xef\xbb\xbf" + ROWS.encode().replace(b"\n", b"\r\n"))
    t = open(os.path.join(ROOT, "scenes", "paper_ship_tank.toml")).read()
    t = t.replace("duration = 20.0", "duration = 4.0").replace("mesh = [5, 5, 5]", "mesh = [4, 4, 3]")
    t = t.replace("[vessel.hydrostatics]", '[vessel.forced]\nfile = "motion.csv"\n\n[vessel.hydrostatics]')
    (tmp_path / "scene.toml").write_text(t)
    assert main(["check", str(tmp_path / "scene.toml")]) == 0, capsys.readouterr().err
    assert "sway, roll from motion.csv (5 samples, t = 0 to 4 s)" in capsys.readouterr().out


def test_a_spreadsheet_scatter_table_reads(tmp_path):
    path = tmp_path / "scatter.csv"
    path.write_bytes(b"\xef\xbb\xbfhs,tp,probability\r\n1.0,6.0,0.75\r\n2.0,8.0,0.25\r\n")
    s = read_scatter(str(path))
    assert list(s.hs) == [1.0, 2.0] and list(s.tp) == [6.0, 8.0]
