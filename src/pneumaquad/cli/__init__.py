"""The command line: one module per command group; ``pneumaquad.cli.main:main`` is the
entry point.

:data:`COMMAND_STARTED` is the ``time.perf_counter()`` reading taken when the command
line is first imported, before its modules load: a command's real-time factor "end to
end" and its ``--profile`` count from there (the interpreter's own start, some tens of
milliseconds, comes before it).
"""

import time

#: ``time.perf_counter()`` when the command line started loading [s].
COMMAND_STARTED = time.perf_counter()
