"""What the board model (emulator), the card tool (sdcard_image), the reference renderer
(reference) and tools/ share as vocabulary: the exit statuses of their commands
(exit_status.py) and the firmware's fatal error codes, read from the firmware's own
firmware/include/errors.inc (firmware_errors.py).

It imports nothing of the project's other packages, so that every one of them may import it."""
