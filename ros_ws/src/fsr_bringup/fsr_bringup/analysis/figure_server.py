"""What the figures' fork server imports (:data:`fsr_bringup.analysis.figure_jobs.WORKER_MODULES`): the figures,
and one throwaway figure drawn in memory (:func:`fsr_bringup.analysis.figures.warm_up`), so that every worker the
server forks starts with matplotlib's caches filled. Importing this module draws that figure and has the process
end without the interpreter's teardown: the server ends with the command that started it, and freeing
matplotlib's and numba's objects one by one took it 0.2-0.3 s of CPU after the command had ended, taken from
whatever ran next. It is meant for the fork server only."""

import atexit

from fsr_bringup.analysis.figures import warm_up
from fsr_bringup.cli.entry_points import exit_now

warm_up()
# Registered after multiprocessing's own exit handler, so run before it, which it skips: the server has no child
# process or finalizer of its own to clean up (its workers are forked raw and leave through os._exit).
atexit.register(exit_now, 0)
