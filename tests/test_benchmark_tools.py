"""benchmarks/run.py's --profile and --markdown, through one small benchmark script: the
profile table splits a row's wall time into launch, kernel, transfer and host, and the
markdown holds the machine, the versions, the date and every row of the run; a generator's
row gives its output GB/s and its share of np.copyto's for the same bytes."""

import json
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

import common  # noqa: E402


def test_profile_and_markdown_of_one_benchmark(tmp_path):
    out, data = tmp_path / "table.markdown", tmp_path / "rows.json"
    done = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "bench_random.py"), "--quick",
                           "--profile", "--markdown", str(out), "--out", str(data)],
                          capture_output=True, text=True, timeout=600, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    profile = done.stdout.split("where the time goes")[1].splitlines()
    header = profile[1].split()
    assert header[:3] == ["case", "size", "device"] and "kernel" in header and "transfer" in header
    rows = [line for line in profile[3:] if line.startswith("random")]
    assert rows
    for line in rows:
        numbers = [float(x) for x in line.split()[-6:]]        # wall, launches, launch..host
        wall, launches, launch, kernel, transfer, host = numbers
        assert launches >= 1 and kernel > 0
        assert launch + kernel + transfer <= wall * 1.05 + 1e-3 and host >= 0
    text = out.read_text()
    assert re.search(r"Measured \d{4}-\d\d-\d\d \d\d:\d\d UTC in one run of `python "
                     r"benchmarks/bench_random.py", text)
    assert "numpy " in text and "pyopencl " in text and "clsamp " in text
    table = [line for line in text.splitlines() if line.startswith("| random")]
    printed = [line for line in done.stdout.split("where the time goes")[0].splitlines()
               if line.startswith("random")]
    assert len(table) == len(printed) > 0
    assert "| GB/s | copyto GB/s | of copyto |" in text
    # every row: the output bytes are the points' float64 bytes, its GB/s and fraction follow
    rows = json.loads(data.read_text())["rows"]
    assert len(rows) == len(printed)
    for row in rows:
        r, n, d = (int(x) for x in row["size"].removesuffix("D").split("x"))
        assert row["output_bytes"] == r * n * d * 8 and row["copy_gbs"] > 0
        assert abs(row["gbs"] - row["output_bytes"] / row["seconds"] / 1e9) <= 1e-9 * row["gbs"]
        assert abs(row["copy_fraction"] - row["gbs"] / row["copy_gbs"]) <= 1e-9 * row["copy_fraction"]


def test_row_bandwidth_and_copy_bandwidth(monkeypatch):
    row = common.Row("random", "1x1000x2D", "cpu", 0.5, output_bytes=2 * 10**9, copy_gbs=8.0)
    assert row.gbs == 4.0 and row.copy_fraction == 0.5
    d = row.as_dict()
    assert d["gbs"] == 4.0 and d["copy_fraction"] == 0.5 and d["output_bytes"] == 2 * 10**9
    plain = common.Row("spectrum", "64x4096", "cpu", 0.5, "numpy", 1.0, "max err 1e-12")
    assert plain.gbs is None and plain.copy_fraction is None and plain.as_dict()["gbs"] is None

    # a table without a generator's row keeps its columns; with one, it has the three more
    import io
    buffer = io.StringIO()
    common.print_table([plain], buffer)
    assert "GB/s" not in buffer.getvalue() and buffer.getvalue().split()[-1] == "1e-12"
    buffer = io.StringIO()
    common.print_table([row, plain], buffer)
    cells = [re.split(r"\s{2,}", line.strip()) for line in buffer.getvalue().splitlines()]
    assert cells[0][7:] == ["GB/s", "copyto GB/s", "of copyto", "quality"]
    assert cells[2][7:10] == ["4", "8", "50%"] and cells[3][7:10] == ["-"] * 3

    # copy_bandwidth counts the bytes written once, over timed's seconds, and copies
    seen = []

    def fake_timed(fn, **kwargs):
        seen.append(fn())
        return 0.002, None

    monkeypatch.setattr(common, "timed", fake_timed)
    assert common.copy_bandwidth(8 * 10**6) == 8 * 10**6 / 0.002 / 1e9 == 4.0
    assert seen == [None]
    monkeypatch.undo()
    measured = common.copy_bandwidth(2**20, repeats=3)
    assert 0.1 < measured < 10**4


def test_markdown_goes_between_the_readme_markers(tmp_path):
    readme = tmp_path / "README.md"
    readme.write_text(f"# title\n\nbefore\n{common.TABLE_BEGIN}\nold table\n{common.TABLE_END}\nafter\n")
    text = common.with_table(str(readme), "| new |\n")
    assert text == f"# title\n\nbefore\n{common.TABLE_BEGIN}\n| new |\n{common.TABLE_END}\nafter\n"
    assert common.with_table(str(tmp_path / "table.markdown"), "| new |\n") == "| new |\n"
    plain = tmp_path / "plain.markdown"
    plain.write_text("no markers\n")
    assert common.with_table(str(plain), "| new |\n") == "| new |\n"


def test_the_readme_summary_and_the_full_table_are_one_run():
    text = (ROOT / "README.md").read_text()
    assert text.count(common.TABLE_BEGIN) == 1 and text.count(common.TABLE_END) == 1
    summary = text.split(common.TABLE_BEGIN)[1].split(common.TABLE_END)[0]
    full = (ROOT / common.FULL_TABLE).read_text()
    when = r"Measured \d{4}-\d\d-\d\d \d\d:\d\d UTC in one run of"
    assert len(re.findall(when, summary)) == 1 and len(re.findall(when, full)) == 1
    assert re.search(when + ".*", summary).group(0) == re.search(when + ".*", full).group(0)
    assert summary.count("| capability | peer | cases |") == 1 and full.count("| case | size | device |") == 1
    assert len(summary.splitlines()) < 70      # with several devices, a side-by-side table too


def test_markdown_writes_the_summary_and_the_full_table_beside(tmp_path):
    readme = tmp_path / "README.md"
    readme.write_text(f"# title\n{common.TABLE_BEGIN}\nold\n{common.TABLE_END}\nafter\n")
    def row(case, seconds, peer, peer_seconds):
        return common.Row(case, "64x2D", "[0] cpu", seconds, peer, peer_seconds,
                          capability="lowdiscrepancy")
    rows = [row("sobol", 0.001, "scipy Sobol unscrambled", 0.01),
            row("sobol", 0.001, "numpy reference", 0.05),
            row("halton", 0.002, "scipy Sobol unscrambled", 0.01)]
    common.write_markdown(str(readme), rows)
    text = readme.read_text()
    assert text.startswith("# title\n") and text.endswith("after\n") and "old" not in text
    assert "| lowdiscrepancy | scipy Sobol unscrambled | 2 | 5× – 10× |" in text
    assert "numpy reference" not in text                  # the NumPy twin is not an outside peer
    full = (tmp_path / common.FULL_TABLE).read_text()
    assert full.count("| sobol |") == 2 and "| halton |" in full


def test_several_devices_are_put_side_by_side(tmp_path):
    def row(case, device, seconds, peer="numpy reference", capability="random"):
        return common.Row(case, "64x2D", device, seconds, peer, 1.0, capability=capability)
    rows = [row("a", "[0] PoCL", 0.2), row("a", "[0] PoCL", 0.2, peer="scipy"),
            row("b", "[0] PoCL", 0.1, capability="sobol"), row("a", "[3] Intel", 0.1),
            row("a", "[3] Intel", 0.1, peer="scipy"), row("b", "[3] Intel", 0.4, capability="sobol"),
            row("c", "[0] PoCL", 0.3),                      # on one device only: left out
            row("d", "[0] PoCL", 0.5, capability="metrics"),
            row("d", "[1] rusticl", 0.1, capability="metrics"),   # Intel refused it
            row("a", "[1] rusticl", 0.4)]
    devices = ["[0] PoCL", "[3] Intel", "[1] rusticl"]
    assert common.across_devices(rows, devices) == [
        ("a", "64x2D", [0.2, 0.1, 0.4]), ("b", "64x2D", [0.1, 0.4, None]),
        ("d", "64x2D", [0.5, None, 0.1])]
    full = common.cross_device_markdown(rows)
    assert "| a | 64x2D | 0.2 | 0.1 | 0.4 | 2.00× | 0.50× | [3] Intel |" in full
    assert "| b | 64x2D | 0.1 | 0.4 | - | 0.25× | - | [0] PoCL |" in full
    assert "| d | 64x2D | 0.5 | - | 0.1 | - | 5.00× | [1] rusticl |" in full
    summary = common.implementation_summary(rows)
    assert "| random | 1 | 0 | 1 | 0 | 2× | 0.5× |" in summary
    assert "| sobol | 1 | 1 | 0 | 0 | 0.25× | - |" in summary
    assert "| metrics | 1 | 0 | 0 | 1 | - | 5× |" in summary
    assert common.implementation_summary(rows[:3]) == "" == common.cross_device_markdown(rows[:3])
    readme = tmp_path / "README.md"
    readme.write_text(f"{common.TABLE_BEGIN}\n{common.TABLE_END}\n")
    common.write_markdown(str(readme), rows)
    assert "fastest on [3] Intel" in readme.read_text()
    assert "## Side by side" in (tmp_path / common.FULL_TABLE).read_text()


def test_the_summary_keeps_outside_peers_that_finished():
    rows = [common.Row("a", "1", "cpu", 1.0, "scipy Sobol scrambled", 3.0, capability="lowdiscrepancy"),
            common.Row("b", "1", "cpu", 1.0, "clsamp fast in double", 0.1, capability="spectrum"),
            common.Row("c", "1", "cpu", 1.0, "numpy twin", 9.0, capability="gbn"),
            common.Row("d", "1", "cpu", 4.0, "qmcpy CubQMCLatticeG", 0.5, capability="cubature",
                       extra={"peer_unconverged": True}),
            common.Row("e", "1", "cpu", 1.0, "qmcpy CubQMCLatticeG", 2.0, capability="cubature")]
    table = common.summary_table(rows, "measured")
    assert "| lowdiscrepancy | scipy Sobol scrambled | 1 | 3× |" in table
    assert "| cubature | qmcpy CubQMCLatticeG | 1 | 2× |" in table          # not the 0.125x
    assert "in double" not in table and "numpy twin" not in table
