"""``amlip-qp sweep``: many deterministic walks over a grid or a random sample of ``walk`` options.

One concept per module: :mod:`~amlip_qp.sweep.spec` (the TOML spec and
``--grid``), :mod:`~amlip_qp.sweep.cells` (a cell, its id and seed),
:mod:`~amlip_qp.sweep.run_cell` (a cell -> one walk -> metrics, or per cell the
largest surviving value of one parameter by
:func:`~amlip_qp.experiments.robustness.largest_surviving`),
:mod:`~amlip_qp.sweep.backends` (a local process pool or Ray tasks),
:mod:`~amlip_qp.sweep.results` (the output folder), :mod:`~amlip_qp.sweep.figures`,
:mod:`~amlip_qp.sweep.cli` (the command handler) and :mod:`~amlip_qp.sweep.bench`
(``amlip-qp bench sweep``). Nothing outside this package imports it but the CLI
(by name, when the subcommand runs).
"""
