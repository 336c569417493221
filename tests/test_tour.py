"""`clsamp tour --quick`: the main job runs end to end and its page is whole."""

import json
import os
import re
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


@pytest.fixture(scope="module")
def tour(tmp_path_factory):
    out = tmp_path_factory.mktemp("tour")
    env = dict(os.environ, PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    done = subprocess.run([sys.executable, "-m", "clsamp", "tour", "--quick", "--no-progress",
                           "--out", str(out)], capture_output=True, text=True, env=env, timeout=600)
    assert done.returncode == 0, done.stderr
    return out


def test_every_section_is_present_and_none_failed(tour):
    from clsamp.tour import SECTIONS
    page = (tour / "index.html").read_text()
    for key, title, _ in SECTIONS:
        assert f"id='{key}'" in page, title
    assert "This section failed" not in page, page[page.find("This section failed"):][:3000]
    # a section can also fail in one of its parts (section 4) or in one row (a sampler)
    assert "class='error'" not in page, page[page.find("class='error'"):][:3000]
    assert "failed:" not in page, page[page.find("failed:") - 500:][:3000]


def test_every_linked_file_exists(tour):
    page = (tour / "index.html").read_text()
    links = re.findall(r'(?:src|href)="([^"#]+)"', page) + re.findall(r"(?:src|href)='([^'#]+)'", page)
    assert any(link.endswith(".png") for link in links)
    for link in links:
        assert (tour / link).exists(), link


def test_json_parses_and_holds_every_section(tour):
    from clsamp.tour import SECTIONS
    data = json.loads((tour / "tour.json").read_text())
    assert set(data["sections"]) == {key for key, _, _ in SECTIONS}
    assert all(s["error"] is None for s in data["sections"].values())


def test_every_stability_case_holds_and_every_sampler_is_shown(tour):
    from clsamp.samplers import sampler_names
    from clsamp.tour import TOUR_SAMPLERS
    sections = json.loads((tour / "tour.json").read_text())["sections"]
    cases = sections["stability"]["data"]
    assert cases and all(case["passed"] for case in cases.values()), cases
    shown = sections["samplers"]["data"]
    for name, _ in TOUR_SAMPLERS:
        assert name in sampler_names(), name
        assert "error" not in shown[name], shown[name].get("error")
    convergence = dict(sections["convergence"]["data"])
    families = convergence.pop("families")
    verdicts = [c["comparison"]["verdict"].split()[0] for c in convergence.values()]
    assert verdicts and set(verdicts) <= {"matches", "pre-asymptotic", "differs", "unknown"}
    # the family sweeps: every family and sampler of the plan, each with its verdict
    from clsamp.tour import TOUR_FAMILIES, TOUR_FAMILY_SAMPLERS
    assert set(families) == {f"{s} / {f}" for f in TOUR_FAMILIES for s in TOUR_FAMILY_SAMPLERS}
    assert all(c["comparison"]["verdict"] in ("matches", "pre-asymptotic", "differs", "unknown")
               for c in families.values())
