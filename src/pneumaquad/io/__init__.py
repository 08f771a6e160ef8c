"""Run folders and recordings (one writer, one reader), lab-data import and the
interruption handling that keeps a recording readable."""
