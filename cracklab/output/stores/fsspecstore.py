"""Stores at fsspec URLs (``s3://bucket/run.zarr``, ``gs://``, ``memory://``, ...): checked
by ``cracklab.output.objectstore.check_url``, written by zarr from the URL. Not locked,
no checkpoints (see docs/guide/reliability.md)."""
from __future__ import annotations

from .base import Store


class FsspecStore(Store):
    """A store at a URL whose scheme names an fsspec implementation."""

    kind = "fsspec"
    accepts = "fsspec URLs (s3://, gs://, az://, memory://, ...)"

    @classmethod
    def handles(cls, scheme: str) -> bool:
        import fsspec

        if not scheme:
            return False
        try:
            fsspec.get_filesystem_class(scheme)
        except ValueError:
            return False
        except ImportError:
            return True       # known, its package missing: check says so
        return True

    def check(self, *, exists: bool = False):
        """``objectstore.check_url``: its scheme's package, credentials, bucket (and, with
        ``exists``, its zarr.json); returns (fsspec filesystem, path)."""
        from ..objectstore import check_url

        return check_url(self.target, exists=exists)

    def zarr_store(self):
        return self.target
