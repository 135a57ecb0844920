"""Physics checks against closed form (``fabmd validate ...``).

Each check runs a real LAMMPS scene and returns a JSON-able dict with the
expected and measured values, the relative error, the tolerance and ``passed``.
"""
