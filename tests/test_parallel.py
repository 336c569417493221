"""Sweeps in tasks: on a Dask LocalCluster the same bits as in-process; a dying worker
loses nothing; checkpoints resume and refuse what is not theirs; clear errors."""

import hashlib
import os
import signal
import threading
import time

import numpy as np
import pytest

import clsamp
from clsamp import parallel
from clsamp.errors import InvalidArgumentError
from clsamp.metrics import discrepancy_sweep


@pytest.fixture
def small_tasks(monkeypatch):
    # many small tasks, so blocks really split (the client cuts the sweep, not the workers)
    monkeypatch.setattr(parallel, "TASK_WORK", 2**12)


@pytest.fixture(scope="module")
def client():
    pytest.importorskip("distributed")
    c = parallel.connect("local:2")
    yield c
    c.close()


def _same(a, b):
    return len(a) == len(b) and all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))


def test_convergence_on_a_cluster_is_bit_identical(client, small_tasks):
    kw = dict(realizations=40, seed=3, progress=False)
    here = clsamp.convergence("jittered", "disk", [16, 64, 256], **kw)
    there = clsamp.convergence("jittered", "disk", [16, 64, 256], client=client, **kw)
    assert _same(here.errors, there.errors) and np.array_equal(here.mse, there.mse)
    fam_here = clsamp.convergence("sobol:owen", "random_heavisides", [16, 64], members=12, **kw)
    fam_there = clsamp.convergence("sobol:owen", "random_heavisides", [16, 64], members=12,
                                   client=client, **kw)
    assert _same(fam_here.errors, fam_there.errors)
    numpy_here = clsamp.convergence("random", "gaussian", [32], backend="numpy", **kw)
    numpy_there = clsamp.convergence("random", "gaussian", [32], backend="numpy", client=client, **kw)
    assert _same(numpy_here.errors, numpy_there.errors)


def test_spectrum_metrics_and_renders_on_a_cluster_are_bit_identical(client, small_tasks):
    s = clsamp.make_sampler("jittered", seed=2)
    here = clsamp.expected_spectrum(s, 256, 12, resolution=32, progress=False)
    there = clsamp.expected_spectrum(s, 256, 12, resolution=32, client=client, progress=False)
    assert np.array_equal(here, there) and here[16, 16] == 256.0
    # the blocks' sum equals the one-batch mean to rounding
    np.testing.assert_allclose(here, clsamp.power_spectrum(s.sample(256, realizations=12), resolution=32),
                               rtol=1e-12, atol=1e-9)
    sweep_here = discrepancy_sweep(clsamp.make_sampler("sobol:owen", seed=1), [64, 256], realizations=6)
    sweep_there = discrepancy_sweep(clsamp.make_sampler("sobol:owen", seed=1), [64, 256], realizations=6,
                                    client=client)
    for method in sweep_here:
        assert np.array_equal(sweep_here[method].values, sweep_there[method].values)
    from clsamp import render
    images_here, _ = render.render_sweep("ao", ["random", "jittered"], [16], 12, seed=1, progress=False)
    images_there, _ = render.render_sweep("ao", ["random", "jittered"], [16], 12, seed=1, client=client,
                                          progress=False)
    assert images_here.keys() == images_there.keys()
    assert all(np.array_equal(images_here[k], images_there[k]) for k in images_here)
    direct = render.render("ao", "jittered", 16, 12, seed=1, progress=False)
    assert np.array_equal(direct, images_here[("jittered", 16)])


def test_a_worker_dying_mid_sweep_loses_nothing(small_tasks):
    pytest.importorskip("distributed")
    c = parallel.connect("local:2")
    try:
        kw = dict(realizations=192, seed=5, progress=False)
        ns = [256, 1024, 4096]
        here = clsamp.convergence("random", "gaussian", ns, **kw)
        found = {}

        def sweep():
            found["result"] = clsamp.convergence("random", "gaussian", ns, client=c, **kw)

        thread = threading.Thread(target=sweep)
        thread.start()
        deadline = time.time() + 60
        while time.time() < deadline and not any(c.processing().values()):
            time.sleep(0.02)
        time.sleep(0.2)
        victim = sorted(c.scheduler_info()["workers"])[0]
        pid = c.run(os.getpid, workers=[victim])[victim]
        os.kill(pid, signal.SIGKILL)              # the worker process dies mid-task
        thread.join(timeout=300)
        assert not thread.is_alive()
        assert _same(here.errors, found["result"].errors)
    finally:
        c.close()


def test_checkpoint_resumes_a_stopped_sweep(tmp_path, monkeypatch):
    monkeypatch.setattr(parallel, "TASK_WORK", 64)    # 6 + 12 blocks
    kw = dict(realizations=24, seed=1, progress=False)
    whole = clsamp.convergence("random", "disk", [16, 32], **kw)
    folder = tmp_path / "ck"
    stored = []
    original = parallel._Checkpoint.store

    def stop_after_three(self, index, value, spent):
        original(self, index, value, spent)
        stored.append(index)
        if len(stored) == 3:
            raise KeyboardInterrupt

    monkeypatch.setattr(parallel._Checkpoint, "store", stop_after_three)
    with pytest.raises(KeyboardInterrupt):
        clsamp.convergence("random", "disk", [16, 32], checkpoint=folder, **kw)
    monkeypatch.setattr(parallel._Checkpoint, "store", original)
    computed = []
    timed = parallel._timed
    monkeypatch.setattr(parallel, "_timed", lambda fn, *a: computed.append(a) or timed(fn, *a))
    resumed = clsamp.convergence("random", "disk", [16, 32], checkpoint=folder, **kw)
    assert _same(whole.errors, resumed.errors)
    tasks = len(list(folder.glob("block-*.npy")))
    assert len(computed) == tasks - 3 > 0
    again = clsamp.convergence("random", "disk", [16, 32], checkpoint=folder, **kw)
    assert _same(whole.errors, again.errors) and len(computed) == tasks - 3
    # the seconds come back with the blocks (they read 0 from a checkpoint, which made
    # time_to_mse free); a checkpoint without them (written before they were kept) gives 0
    assert np.array_equal(again.seconds, resumed.seconds) and (again.seconds > 0).all()
    # the hash covers each block's seconds: one changed is refused ('nan', 1e308 came back)
    took = sorted(folder.glob("block-*.seconds"))[0]
    kept = took.read_text()
    for text in ("nan", "1e308", "-5.0"):
        took.write_text(text)
        with pytest.raises(InvalidArgumentError, match="corrupt"):
            clsamp.convergence("random", "disk", [16, 32], checkpoint=folder, **kw)
    took.write_text(kept)
    # a checkpoint written before the seconds were kept (its hash of the block alone) gives 0
    for took in folder.glob("block-*.seconds"):
        block = took.with_suffix(".npy").read_bytes()
        took.with_suffix(".sha256").write_text(hashlib.sha256(block).hexdigest())
        took.unlink()
    assert (clsamp.convergence("random", "disk", [16, 32], checkpoint=folder, **kw).seconds == 0).all()


def test_a_checkpointed_sweep_builds_its_kernels_before_the_clock(tmp_path, monkeypatch):
    # without a warm-up the first n's seconds held the builds, stored and replayed on resume
    from clsamp import estimates
    warmed = []
    original = estimates._Estimator.warm_up
    monkeypatch.setattr(estimates._Estimator, "warm_up",
                        lambda self, n: warmed.append(n) or original(self, n))
    clsamp.convergence("random", "disk", [16, 32], realizations=8, checkpoint=tmp_path / "ck", progress=False)
    assert warmed == [16]


def test_a_foreign_or_corrupt_checkpoint_is_refused(tmp_path, monkeypatch):
    monkeypatch.setattr(parallel, "TASK_WORK", 64)
    kw = dict(realizations=8, seed=1, progress=False)
    folder = tmp_path / "ck"
    clsamp.convergence("random", "disk", [16, 64], checkpoint=folder, **kw)
    with pytest.raises(InvalidArgumentError, match="holds another sweep"):
        clsamp.convergence("random", "disk", [16, 64], checkpoint=folder, realizations=8, seed=2,
                           progress=False)
    block = sorted(folder.glob("block-*.npy"))[0]
    block.write_bytes(block.read_bytes()[:-8] + b"\0" * 8)
    with pytest.raises(InvalidArgumentError, match="SHA-256"):
        clsamp.convergence("random", "disk", [16, 64], checkpoint=folder, **kw)
    stranger = tmp_path / "other"
    stranger.mkdir()
    (stranger / "notes.txt").write_text("mine")
    with pytest.raises(InvalidArgumentError, match="not a clsamp checkpoint"):
        clsamp.convergence("random", "disk", [16], checkpoint=stranger, **kw)


def test_bad_clients_and_unreachable_schedulers_are_clear_errors():
    pytest.importorskip("distributed")
    with pytest.raises(InvalidArgumentError, match="'client' must be a dask.distributed.Client"):
        clsamp.convergence("random", "disk", [16], realizations=4, client="tcp://localhost:8786",
                           progress=False)
    t0 = time.time()
    with pytest.raises(InvalidArgumentError, match="cannot reach a Dask scheduler"):
        parallel.connect("tcp://127.0.0.1:9", timeout=2)
    assert time.time() - t0 < 20
    with pytest.raises(InvalidArgumentError, match="local:N"):
        parallel.connect("local:many")


def test_block_ranges_cover_in_order():
    blocks = parallel.block_ranges(103, 10, work=95)
    assert blocks[0] == (0, 9) and blocks[-1][1] == 103
    assert all(a[1] == b[0] for a, b in zip(blocks, blocks[1:], strict=False))
