"""Import open3d with a one-line, actionable error instead of a loader traceback."""

from __future__ import annotations


def import_open3d():
    """Return the ``open3d`` module or raise ImportError with the fix in one line.

    open3d 0.20 from pip links the system library ``libusb-1.0.so.0`` that fresh
    Debian machines lack (DESIGN.md section 8).
    """
    try:
        import open3d
    except (ImportError, OSError) as e:
        if "libusb" in str(e):
            raise ImportError(
                "open3d cannot load libusb-1.0.so.0: install it with `apt-get install -y libusb-1.0-0`"
            ) from None
        raise ImportError(f"open3d is not importable ({e}); `pip install open3d`") from None
    return open3d
