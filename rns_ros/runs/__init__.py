"""Runs of rns_demo's scenarios over DDS: one method on a fresh stack, its recorded figures, and
the tables of the rows (:mod:`~rns_ros.runs.report`)."""
