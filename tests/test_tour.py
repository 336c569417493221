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
    (out.parent / "stderr.txt").write_text(done.stderr)
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


# -- issue 40: a page without glitches ------------------------------------------------------
def test_the_page_has_no_nan(tour):
    page = (tour / "index.html").read_text()
    found = [m.start() for m in re.finditer(r"\bnan\b", page, re.IGNORECASE)]
    assert not found, [page[i - 200:i + 20] for i in found[:3]]
    assert "too few N" in page      # the quick sweeps' slopes over two N say so in words


def test_section_timings_are_labelled(tour):
    page = (tour / "index.html").read_text()
    assert not re.search(r"<p class='note'>[0-9.]+ s</p>", page)
    from clsamp.tour import SECTIONS
    assert len(re.findall(r"Section computed in [0-9.]+ s\.", page)) == len(SECTIONS)


def test_the_device_table_is_in_human_units(tour):
    device = (tour / "index.html").read_text().split("id='device'")[1]
    assert not re.search(r"<td>[0-9]{7,}</td>", device), "raw bytes"
    assert "('cl_" not in device and "GiB" in device


def test_one_name_per_sampler(tour):
    page = (tour / "index.html").read_text()
    samplers = page.split("id='samplers'")[1].split("id='convergence'")[0]
    assert "<td>sobol:owen</td>" in samplers and "<td>sobol</td>" not in samplers
    data = json.loads((tour / "tour.json").read_text())["sections"]["samplers"]["data"]
    assert data["sobol"]["label"] == "sobol:owen"


def test_warnings_print_as_one_line(tour):
    err = (tour.parent / "stderr.txt").read_text()
    assert "it/s]" not in err and "s/it]" not in err, err     # --no-progress: no sampler's bar
    assert "UserWarning" not in err and "warnings.warn" not in err, err
    assert all(line.startswith("clsamp: warning: ") for line in err.splitlines()
               if "warning" in line.lower()), err


def test_accuracy_against_time_is_timed_as_medians(tour):
    cost = json.loads((tour / "tour.json").read_text())["sections"]["cost"]["data"]
    from clsamp.tour_cost import REPEATS
    assert REPEATS >= 3
    per_estimate = cost["samplers"]["disk"]["seconds_per_estimate"]
    assert set(per_estimate) >= {"random", "sobol:owen"}
    assert all(len(v) == 4 and min(v) > 0 for v in per_estimate.values())
    assert f"median of {REPEATS}" in (tour / "index.html").read_text()


def test_the_blue_noise_section_compares_the_optimizers_and_renders_depth_of_field(tour):
    # issue 37: quality against seconds for every registered optimizer; 4-D sets in a render
    from clsamp.samplers import sampler_names
    from clsamp.tour_blue import BLUE_NOISE, DOF_SAMPLERS
    data = json.loads((tour / "tour.json").read_text())["sections"]["blue_noise"]["data"]
    shown = [name for name, _ in BLUE_NOISE if name in sampler_names()]
    assert "gbn" in shown and all("error" not in data[name] for name in shown), data
    for name in shown:
        assert data[name]["seconds"] > 0 and 0 < data[name]["rho"] <= 1
    assert data["gbn"]["low_frequency_power"] < data["poisson_disk"]["low_frequency_power"] / 5
    dof = data["depth_of_field"]
    assert set(dof) == set(DOF_SAMPLERS) and all(dof[s]["mse"] > 0 for s in dof)
    assert dof["gbn"]["mse"] < dof["random"]["mse"]
    assert (tour / "img" / "blue_quality_time.png").exists()


def test_the_qmc_section_costs_integrate_by_method_and_fits_higher_order_rates(tour):
    # issue 38: integrate's cost against tolerance for the three methods; higher-order rates
    from clsamp.tour_qmc import METHODS, ORDERS, tour_qmc_plan
    data = json.loads((tour / "tour.json").read_text())["sections"]["qmc"]["data"]
    _, tolerances, _, _ = tour_qmc_plan(quick=True)
    for label, _ in METHODS:
        run = data["integrate"][label]
        assert run["tolerances"] == list(tolerances) and min(run["seconds"]) > 0, run
        assert all(e <= 2 * t for e, t in zip(run["errors"], tolerances, strict=True)), run
    slopes = {label: data["higher_order"][label]["comparison"]["slope"] for label, _ in ORDERS}
    assert slopes["order 2, digital shift"] < slopes["order 1, Owen scrambling"] < -2.5, slopes
    assert (tour / "img" / "qmc_cost.png").exists() and (tour / "img" / "qmc_higher_order.png").exists()
