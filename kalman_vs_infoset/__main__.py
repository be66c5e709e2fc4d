import sys

from kalman_vs_infoset._entry import main

sys.exit(main())
