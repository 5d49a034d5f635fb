"""torquebench harness: robots, data generation, baseline, replay, reports, CLI."""
