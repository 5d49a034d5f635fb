"""Robot in, results out: the measurements the bench's sections, the studies and the sweeps
share (identification against the oracle, ...). No printing, no files: plain results."""
