"""What users drive the board model with: the command line (cli.py), run output and golden frames
(output.py, golden.py, grab.py), the GDB stub (gdbstub.py), instruction traces, profiles and VCD
pin logs (trace.py, profile.py, vcd.py), console expectations (console_watch.py) and UART input
(uart_input.py).

May import: anything in emulator."""
