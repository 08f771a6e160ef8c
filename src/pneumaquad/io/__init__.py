"""Run folders (:mod:`.run_folder`: one versioned layout, one writer, one reader) and the
table files below them (:mod:`.tables`), lab-data import (:mod:`.measured`) and the
interruption handling that keeps a recording readable."""
