"""``python -m skfem_flex``: the ``skfem-flex`` command."""
from .apps.cli import main

raise SystemExit(main())
