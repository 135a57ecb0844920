"""Protocols: each turns a described test into a LAMMPS run and reduces its results."""
