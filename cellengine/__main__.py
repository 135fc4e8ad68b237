import sys

from cellengine.cli import main

sys.exit(main())
