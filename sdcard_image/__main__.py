"""`python -m sdcard_image`: see `sdcard_image.cli`."""
import sys

from .cli import main

sys.exit(main())
