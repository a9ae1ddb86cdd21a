"""``python -m skfem_flex.apps.cli``: the ``skfem-flex`` command."""
from . import main

if __name__ == "__main__":
    raise SystemExit(main())
