"""``python -m bikerider`` runs the command line."""

import sys

from bikerider.cli import main

sys.exit(main())
