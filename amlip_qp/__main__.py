"""``python -m amlip_qp``: the ``amlip-qp`` command."""

import sys

from amlip_qp.cli import main

sys.exit(main())
