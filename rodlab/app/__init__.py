"""The application layer of rodlab: the ``rodlab`` command (:mod:`rodlab.app.cli`), the demo pipeline
(:mod:`rodlab.app.pipeline`), the diagnosis (:mod:`rodlab.app.diagnose`), design studies
(:mod:`rodlab.app.study`) and reports (:mod:`rodlab.app.report`).

It may import everything below it (the domain packages ``rodlab.geometry``, ``rodlab.fea``,
``rodlab.stiffness_rig``, ``rodlab.calibrate`` and the core); nothing below imports it
(import-linter contracts in ``pyproject.toml``, docs/architecture.md).
"""

__all__: list[str] = []
