"""``python -m dda``: the same as the ``dda`` command."""

from dda.cli import main

raise SystemExit(main())
