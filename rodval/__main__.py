import sys

from rodval.cli import main

sys.exit(main())
