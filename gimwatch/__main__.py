"""``python -m gimwatch``."""

import sys

from gimwatch.cli import main

sys.exit(main())
