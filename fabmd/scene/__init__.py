"""The LAMMPS scene: input text rendered from ``lammps_templates/``.

Protocols compose an input from fragments in a fixed order — setup, bonds,
contact, protocol fixes, guards, outputs, run — each rendered by a function of
:mod:`fabmd.scene.blocks` that fills numbers into a template.
"""
