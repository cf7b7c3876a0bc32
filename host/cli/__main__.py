"""`python3 -m host.cli ...`: the `staregen` command without its installed script (a checkout on PYTHONPATH)."""
import sys

from host.cli import main

sys.exit(main())
