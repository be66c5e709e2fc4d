import sys

from kalman_vs_infoset.experiments.cli import main

sys.exit(main())
