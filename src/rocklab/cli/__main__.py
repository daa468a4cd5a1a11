"""``python -m rocklab.cli``: the ``rocklab`` command."""

from rocklab.cli import main

raise SystemExit(main())
