"""The project's benchmark: held-out test split, every method through the transfer diagram, the strict judge,
bootstrap intervals.

- :mod:`catgrasp_drake.benchmark.runner`: splits, placements, the trial task, ``run_benchmark``;
- :mod:`catgrasp_drake.benchmark.stats`: bootstrap intervals over instances, paired differences;
- :mod:`catgrasp_drake.benchmark.report`: records files and the Markdown tables built from them.
"""
