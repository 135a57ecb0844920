"""Results: run folders, curves, summaries, plots and trajectories.

* :mod:`.folder` — run folders, CSV/JSON;
* :mod:`.plots` — curves and fields with units on the axes;
* :mod:`.trajectory` — ``trajectory.h5`` (H5MD) from the LAMMPS dumps (``finalise``;
  dump readers: :mod:`fabmd.engine.lammps_dump`, file readers:
  :mod:`fabmd.analysis.trajectory_file`);
* :mod:`.paraview` — ``trajectory.pvd`` + ``paraview/frame_*.vtu``;
* :mod:`.universe` — :func:`fabmd.load`, results as MDAnalysis universes;
* :mod:`.fibre_angles` — the fibre shear angle of a zone, frame by frame.
"""
