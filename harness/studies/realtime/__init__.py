"""Study `realtime` (entry point: .section.run): Algorithm 2 on random obstacle scenarios,
timed and replayed per planner (the measurement: .measure)."""
