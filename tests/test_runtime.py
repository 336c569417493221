"""The OpenCL runtime: devices, device choice, the built-program cache, build errors."""

import os
import re
import subprocess
import sys

import pytest

import clsamp
from clsamp import runtime
from clsamp.errors import BuildError, ClsampError, InvalidArgumentError, NoDeviceError


def test_devices_lists_a_cpu_device_with_fp64():
    records = clsamp.devices()
    assert records, "no OpenCL device"
    assert any(r.type == "cpu" for r in records)
    default = clsamp.current_device()
    assert default.fp64
    assert str(default).startswith(f"[{default.index}]")


def test_default_is_first_cpu_device_that_compiles():
    if os.environ.get("CLSAMP_DEVICE"):
        pytest.skip("CLSAMP_DEVICE chooses the device")
    first_cpu = next(r for r in clsamp.devices() if r.type == "cpu" and runtime.compiles(r))
    assert clsamp.current_device() == first_cpu


def test_a_device_whose_compiler_fails_is_skipped_and_explained(monkeypatch):
    records = clsamp.devices()
    good = clsamp.current_device()
    # every device but the current one (or all of them) fails the probe, as PoCL 3.0 does on
    # a CPU its LLVM does not know
    for broken_too in (False, True):
        failing = {r.index for r in records if broken_too or r.index != good.index}
        log = ["clBuildProgram failed: BUILD_PROGRAM_FAILURE", "error: unknown target CPU 'generic'"]
        monkeypatch.setattr(runtime.discovery, "_broken", {i: log for i in failing})
        monkeypatch.setattr(runtime.discovery, "_current", None)
        assert not any(runtime.compiles(i) for i in failing)
        if not broken_too:
            assert clsamp.current_device() == good
        else:
            with pytest.raises(NoDeviceError, match="pocl-opencl-icd") as info:
                clsamp.current_device()
            assert "unknown target CPU" in str(info.value)


def test_use_device_by_index_name_and_type():
    record = clsamp.current_device()
    assert clsamp.use_device(record.index) == record
    assert clsamp.use_device(record.name[:6]) == record
    assert clsamp.use_device(record.type) == record
    assert clsamp.use_device(str(record.index)) == record


def test_use_device_errors_name_the_argument():
    with pytest.raises(InvalidArgumentError, match="'device' index"):
        clsamp.use_device(99)
    with pytest.raises(NoDeviceError, match="no OpenCL device matches"):
        clsamp.use_device("no-such-device-xyz")
    with pytest.raises(InvalidArgumentError):
        clsamp.use_device(1.5)


def test_env_variable_chooses_device():
    code = "import clsamp; print(clsamp.current_device().index)"
    env = dict(os.environ, CLSAMP_DEVICE=clsamp.current_device().name[:5])
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         check=True, cwd=os.path.dirname(os.path.dirname(__file__)))
    assert int(out.stdout) == clsamp.current_device().index


def test_second_sampler_call_builds_nothing():
    sampler = clsamp.make_sampler("random", d=2, seed=3)
    sampler.sample(16)
    before = runtime.build_count()
    sampler.sample(32, realizations=3)
    clsamp.make_sampler("random", d=5, seed=4).sample(8)
    assert runtime.build_count() == before


def test_defines_make_distinct_cached_variants():
    before = runtime.build_count()
    a = runtime.program("philox_probe.cl", defines={"CLSAMP_TEST_VARIANT": 1})
    b = runtime.program("philox_probe.cl", defines={"CLSAMP_TEST_VARIANT": 2})
    assert a is not b
    assert runtime.program("philox_probe.cl", defines={"CLSAMP_TEST_VARIANT": 1}) is a
    assert runtime.build_count() == before + 2


def test_build_failure_names_file_device_and_log(tmp_path, monkeypatch):
    (tmp_path / "broken.cl").write_text("__kernel void f(__global float *x) { x[0] = undefined_name; }\n")
    monkeypatch.setattr(runtime.programs, "kernel_folder", lambda: tmp_path)
    with pytest.raises(BuildError) as info:
        runtime.program("broken.cl")
    message = str(info.value)
    assert "kernels/broken.cl" in message
    assert clsamp.current_device().name in message
    assert "undefined_name" in message
    assert isinstance(info.value, ClsampError) and isinstance(info.value, RuntimeError)


def test_headers_are_inlined():
    source = runtime.kernel_source("random.cl")
    assert "#include" not in source
    assert "philox4x32_10" in source


def test_chunk_ranges_cover_everything_without_overlap():
    total = 1000
    item = clsamp.current_device().max_allocation // 40  # forces several chunks
    parts = runtime.chunk_ranges(total, item)
    assert len(parts) > 1
    assert parts[0][0] == 0 and parts[-1][1] == total
    assert all(a[1] == b[0] for a, b in zip(parts, parts[1:], strict=False))


def test_local_size_is_a_power_of_two_within_limits():
    size = runtime.local_size(100)
    assert size & (size - 1) == 0 and size <= min(100, clsamp.current_device().max_work_group_size)


def _code(text):
    """Kernel source without its comments."""
    return re.sub(r"//[^\n]*", "", re.sub(r"/\*.*?\*/", "", text, flags=re.S))


def test_no_kernel_uses_512_bit_vectors():
    # PoCL 3.0 links AVX-512 hosts to its AVX-512 built-in library but compiles kernels for
    # a CPU model LLVM 14 knows (znver3 on a Zen 4): a 512-bit vector (double8, ulong8,
    # float16, ...) passed to or returned from a built-in then crosses two calling
    # conventions, which crashed the Sobol, render and NUFFT kernels and made programs come
    # back from PoCL's binary cache with no kernels at all.
    wide = re.compile(r"\b(?:double|long|ulong)(?:8|16)\b|\b(?:float|int|uint|short|ushort)16\b"
                      r"|\b(?:char|uchar)(?:32|64)\b")
    folder = runtime.kernel_folder()
    names = sorted(p.name for p in folder.iterdir() if p.name.endswith((".cl", ".h")))
    assert names
    offenders = {name: sorted(set(wide.findall(_code((folder / name).read_text()))))
                 for name in names}
    assert not {k: v for k, v in offenders.items() if v}


def test_a_program_from_the_binary_cache_has_its_kernels(tmp_path):
    # a second process builds from PoCL's cache (the first filled it): the kernels are there
    code = ("from clsamp import runtime\n"
            "print(runtime.program('lowdiscrepancy.cl').kernel_names)\n"
            "print(runtime.program('render.cl', {'VW': 8, 'SAMPLES_PHILOX': 1, 'SAMPLES_PHILOX_STREAM': 0,"
            " 'AO_RAYS': 2, 'EFFECT_AA': 1}).kernel_names)\n"
            "print(runtime.program('nufft.cl', {'DIM': 2, 'WIDTH': 16}).kernel_names)\n")
    env = dict(os.environ, POCL_CACHE_DIR=str(tmp_path))
    root = os.path.dirname(os.path.dirname(__file__))
    for _ in range(2):
        out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                             check=True, cwd=root)
        assert out.stdout.split() == ["sobol_points;sobol_points64;lms_matrices;radical_points",
                                      "render_pixels",
                                      "spectrum_spread;spectrum_sum_copies"]


def test_a_double_kernel_never_reaches_a_compiler_without_fp64():
    before = runtime.build_count()
    with runtime.without_fp64():
        assert not runtime.current_device().fp64
        with pytest.raises(NoDeviceError, match=r"kernels/spectrum\.cl .*no cl_khr_fp64"):
            runtime.program("spectrum.cl", defines={"CLSAMP_FP64_PROBE": 1})
        assert runtime.build_count() == before
        # the integer path of random.cl has no double and builds
        runtime.program("random.cl", defines={"CLSAMP_FP64_PROBE": 1})
    assert runtime.current_device().fp64 == runtime.devices()[runtime.current_device().index].fp64
    assert runtime.needs_fp64("spectrum.cl")
    assert not runtime.needs_fp64("random.cl")


def test_active_source_drops_the_branch_a_device_skips():
    source = """a
#if CLSAMP_FP64
double x;
#ifdef OTHER
double y;
#endif
#else
ulong x;
#endif
#if !CLSAMP_FP64
ulong z;
#else
double z;
#endif
#ifndef K
k
#endif
"""
    without = runtime.active_source(source, fp64=False).split()
    assert without == ["a", "ulong", "x;", "ulong", "z;", "#ifndef", "K", "k", "#endif"]
    assert "ulong" not in runtime.active_source(source, fp64=True)


def test_capabilities_of_the_default_device():
    runs = runtime.capabilities()
    assert set(runs) == set(runtime.CAPABILITIES)
    assert all(why is None for why in runs.values()) == runtime.current_device().fp64


def test_what_a_compiler_says_on_success_is_hidden(monkeypatch):
    """Intel's CPU runtime logs every build; pyopencl makes that a CompilerWarning, which
    the runtime hides unless PYOPENCL_COMPILER_OUTPUT=1 asks for it."""
    import warnings

    import pyopencl as cl

    class Chatty:
        def build(self, options=()):
            warnings.warn("Compilation started\nCompilation done", cl.CompilerWarning, stacklevel=2)
            return self

    monkeypatch.delenv("PYOPENCL_COMPILER_OUTPUT", raising=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert isinstance(runtime.discovery._build(Chatty()), Chatty)
    monkeypatch.setenv("PYOPENCL_COMPILER_OUTPUT", "1")
    with pytest.warns(cl.CompilerWarning, match="Compilation started"):
        runtime.discovery._build(Chatty())
