"""``python -m gimwatch.cli``."""

import sys

from gimwatch.cli import main

sys.exit(main())
