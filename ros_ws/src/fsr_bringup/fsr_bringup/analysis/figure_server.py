"""What the figures' fork server imports (:data:`fsr_bringup.analysis.figure_jobs.WORKER_MODULES`): the figures,
and one throwaway figure drawn in memory (:func:`fsr_bringup.analysis.figures.warm_up`), so that every worker the
server forks starts with matplotlib's caches filled. Importing this module draws that figure: it is meant for the
fork server only."""

from fsr_bringup.analysis.figures import warm_up

warm_up()
