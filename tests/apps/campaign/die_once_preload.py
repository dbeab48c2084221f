"""Dask worker preload for the worker-death test (loaded by path through `distributed.worker.preload`):
in each worker process it wraps the campaign kind's `execute` so that the task whose id is in
$TELEOP_TEST_DIE_ONCE_TASK, on its first attempt anywhere, computes its result and then kills its own
worker process with SIGKILL before returning it (the worst moment: the work done, nothing delivered). The
first attempt is claimed by creating the file $TELEOP_TEST_DIE_ONCE_MARK (O_EXCL: one claimant among all
worker processes, restarted ones included); the dying process writes its pid into it."""

import os
import signal


def dask_setup(worker):  # noqa: ARG001 - the preload protocol passes the worker
    from teleop.apps.campaign import blind
    from teleop.apps.campaign.identity import Task

    marked, mark = os.environ["TELEOP_TEST_DIE_ONCE_TASK"], os.environ["TELEOP_TEST_DIE_ONCE_MARK"]
    real = blind.execute

    def execute(identity):
        result = real(identity)
        if Task(blind.KIND, identity, "").id == marked:
            try:
                fd = os.open(mark, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
            except FileExistsError:
                return result  # a later attempt: deliver
            os.write(fd, str(os.getpid()).encode())
            os.close(fd)
            os.kill(os.getpid(), signal.SIGKILL)
        return result

    blind.execute = execute
