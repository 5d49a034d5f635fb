"""Study `realtime_runs`: `plan --realtime` run again and again on the same fresh scenarios,
quiet and under a load the study makes: whether every run keeps the clearance, and how much
the executed energy moves between runs (harness.studies.realtime_runs.section)."""
