"""``python -m benchmarks COMMAND …`` = the installed ``auv-gym COMMAND …`` (`benchmarks.cli`)."""

import sys

from benchmarks.cli import main

sys.exit(main())
