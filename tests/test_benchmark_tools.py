"""benchmarks/run.py's --profile and --markdown, through one small benchmark script: the
profile table splits a row's wall time into launch, kernel, transfer and host, and the
markdown holds the machine, the versions, the date and every row of the run."""

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_profile_and_markdown_of_one_benchmark(tmp_path):
    out = tmp_path / "table.markdown"
    done = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "bench_random.py"), "--quick",
                           "--profile", "--markdown", str(out)],
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
