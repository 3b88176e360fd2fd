"""A function run in a process of its own (softcell.runner.side_process), and a local
cluster that leaves this process' environment as it found it."""

from __future__ import annotations

import os
import signal
import time

import pytest

from softcell.errors import SoftcellError
from softcell.runner.side_process import Alongside


def test_the_result_comes_back_with_the_process_own_time():
    with Alongside(divmod, 17, 5) as job:
        assert job.result() == (3, 2)
    assert job.seconds is not None and job.seconds >= 0


def test_an_error_in_the_process_is_raised_in_the_caller():
    with Alongside(int, "not a number") as job, pytest.raises(ValueError, match="not a number"):
        job.result()


def test_a_process_killed_without_a_result_is_named_with_its_exit_code():
    with Alongside(time.sleep, 60) as job:
        time.sleep(0.5)  # let it start
        os.kill(job._process.pid, signal.SIGKILL)
        with pytest.raises(
            SoftcellError,
            match=r"sleep, run in a process of its own, ended without a result \(exit code -9\)",
        ):
            job.result()


def test_leaving_the_block_early_ends_the_process():
    with pytest.raises(KeyboardInterrupt), Alongside(time.sleep, 60) as job:
        raise KeyboardInterrupt
    assert not job._process.is_alive()


def test_a_local_cluster_leaves_the_environment_as_it_found_it():
    from softcell.runner.cluster import cluster_client

    before = dict(os.environ)
    with cluster_client(1) as client:
        assert client.submit(sum, [1, 2]).result() == 3
    assert dict(os.environ) == before  # dask sets MALLOC_TRIM_THRESHOLD_, OMP_NUM_THREADS...
