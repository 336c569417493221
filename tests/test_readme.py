"""The README's Python examples run as written (a GPU line aside), so the API tour stays true."""

import re
from pathlib import Path

README = Path(__file__).resolve().parent.parent / "README.md"


def test_the_api_tour_runs(tmp_path, monkeypatch):
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)
    assert blocks
    code = "\n".join(blocks).replace('clsamp.use_device("gpu")', 'clsamp.current_device()')
    monkeypatch.chdir(tmp_path)                        # the pictures it writes land here
    monkeypatch.setenv("CLSAMP_CACHE", str(tmp_path))  # and the reference render
    exec(compile(code, str(README), "exec"), {})
    assert {"pd.png", "conv.png", "conv_time.png", "ao.png"} <= {p.name for p in tmp_path.iterdir()}
