"""
``python -m explorer.dev.regenerate_tables``: regenerate every table of ``luts/`` and its manifest.

The tables are declared by the physics modules they belong to (:func:`explorer.tables.luts.register`);
importing those modules registers them, and the store writes each with its checksum. A source checkout
only: an installed package regenerates stale tables into the user cache by itself.
"""

from __future__ import annotations

from explorer import resources
from explorer.physics import colorimetry, lobes_fgd, thinfilm  # noqa: F401  (they register the tables)
from explorer.tables import luts


def main() -> int:
    resources.require_checkout("python -m explorer.dev.regenerate_tables")
    for name in sorted(luts.TABLES):
        table = luts.generate(name)
        print(f"luts/{name}.npy  shape {table.shape}  {luts._sha256(luts.LUT_DIR / f'{name}.npy')[:16]}…")
    print(f"luts/{luts.MANIFEST} written")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
