"""``python3 -m explorer [ARGS...]`` and ``python3 -m explorer test [PYTEST ARGS...]``.

Both set everything up on first use (system packages, ``.venv``), then run the
CLI (``explorer.cli.commands:main``) or pytest.  See ``explorer/dev/bootstrap.py``.
Standard library only: this runs before any dependency is installed.
"""

import sys

from explorer.dev.bootstrap import main

if __name__ == "__main__":
    sys.exit(main())
