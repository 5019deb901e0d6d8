"""``python -m inserr``: the ``inserr`` command (same as the installed script)."""

from __future__ import annotations

import sys

from inserr.cli.main import main

if __name__ == "__main__":  # pragma: no cover - exercised by a subprocess test
    sys.exit(main())
