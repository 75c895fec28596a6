import sys

from upm.cli import main

sys.exit(main())
