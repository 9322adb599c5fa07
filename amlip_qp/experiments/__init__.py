"""The commands' experiments, above the library: ``walk``, ``compare``, ``view``, ``bench``, ``check-robot``.

Each module here runs the library (:mod:`amlip_qp.sim`, :mod:`amlip_qp.control`)
for one command: the command line imports its handler by name when the
command runs, and the sweep (:mod:`amlip_qp.sweep`) reuses the ``walk``
options and the robustness searches. Nothing in the library imports this
package.
"""
