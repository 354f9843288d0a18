"""Checks anyone can run on the project: fuzzing, reproduction of the committed results and
import cycles (`python -m benchmarks.checks.import_cycles`)."""
