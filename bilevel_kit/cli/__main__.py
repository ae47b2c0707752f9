"""``python -m bilevel_kit.cli``."""

import sys

from . import main

sys.exit(main())
