"""``python3 -m explorer [ARGS...]`` and ``python3 -m explorer test [PYTEST ARGS...]``.

In a checkout both set everything up on first use (system packages, ``.venv``), then run the CLI
(``explorer.cli.commands:main``) or pytest: see ``explorer/dev/bootstrap.py`` (standard library only:
this runs before any dependency is installed). An installed wheel has no ``explorer.dev`` (pip brought
the dependencies): there it runs the CLI directly.
"""

import sys


def _installed_main() -> int:
    if sys.argv[1:2] == ["test"]:
        print("error: the tests run from a source checkout (git clone), not an installed package", file=sys.stderr)
        return 1
    from explorer.cli.commands import main as cli

    return cli()


try:
    from explorer.dev.bootstrap import main
except ImportError:  # an installed wheel
    main = _installed_main

if __name__ == "__main__":
    sys.exit(main())
