"""``python -m machinesim``: the command line, as the installed ``machinesim`` script runs it
(`machinesim.cli.main`)."""

import sys

from machinesim.cli import main

sys.exit(main())
