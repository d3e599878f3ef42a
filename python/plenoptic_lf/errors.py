# SPDX-License-Identifier: AGPL-3.0-or-later
"""How decoding refuses: its input (metadata, image) or a missing module; each error carries one
sentence for the user."""


class MetadataError(Exception):
    """The metadata file is missing, unreadable, not JSON, or lacks / garbles a field."""


class DecodeError(Exception):
    """The raw image cannot be decoded with this metadata (size mismatch, no lens inside, a
    light field too large...)."""


class DependencyError(ImportError):
    """A Python module the decoder needs (OpenImageIO) is not installed; the message names the
    Debian and the pip package."""
