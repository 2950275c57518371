import os
import signal
import sys


def _stopped_while_starting(number: int, _frame) -> None:
    """A signal while the command's modules are still being imported (numpy, Unicorn: a few tenths
    of a second), before the command's own handlers (cli.SignalStop) are in place: it ends the
    command there, with the status and the words cli gives a stop before the run began, not a
    KeyboardInterrupt traceback (nor, for SIGTERM, no words at all)."""
    name = signal.Signals(number).name
    kind = "terminated" if number == signal.SIGTERM else "interrupted"
    os.write(2, f"[board] stopped ({kind}): {name} received: the run was stopped there\n".encode())
    os._exit(128 + number)


for _number in (signal.SIGINT, signal.SIGTERM):
    signal.signal(_number, _stopped_while_starting)

from .frontends.cli import main  # noqa: E402  (after the handlers: the imports take a while)

sys.exit(main())
