"""Reading a mesh file with meshio, with errors that name the file: one rule for the planar and spatial loaders."""
from __future__ import annotations

import os

__all__ = ["read_mesh_file"]


def read_mesh_file(path):
    """The ``meshio.Mesh`` in ``path``.

    Raises
    ------
    ValueError
        The path does not exist or is a directory, or meshio cannot read a mesh from it (some of its readers
        end the process with ``sys.exit`` on a bad file: that is caught too).
    """
    import meshio
    if not os.path.isfile(path):
        why = "is a directory, not a mesh file" if os.path.isdir(path) else "does not exist"
        raise ValueError(f"mesh file {str(path)!r} {why}")
    try:
        return meshio.read(path)
    except OSError as exc:
        raise ValueError(f"mesh file {str(path)!r} cannot be read: {exc.strerror or exc}") from None
    except (Exception, SystemExit) as exc:   # noqa: BLE001  meshio's readers fail with many types, even exit
        raise ValueError(f"mesh file {str(path)!r} is not a mesh meshio can read "
                         f"({type(exc).__name__}: {' '.join(str(exc).split())})") from None
