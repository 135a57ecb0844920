"""Results: run folders, curves, summaries, plots and trajectories."""
