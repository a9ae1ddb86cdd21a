"""``python -m skfem_flex``: the ``skfem-flex`` command."""
from .cli import main

raise SystemExit(main())
