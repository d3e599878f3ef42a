# SPDX-License-Identifier: AGPL-3.0-or-later
"""The two ways decoding refuses its input; each carries one sentence for the user."""


class MetadataError(Exception):
    """The metadata file is missing, unreadable, not JSON, or lacks / garbles a field."""


class DecodeError(Exception):
    """The raw image cannot be decoded with this metadata (size mismatch, no lens inside...)."""
