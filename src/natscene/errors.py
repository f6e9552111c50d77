"""
Error classes
=============

Defines the project's two error classes, in a module that imports nothing, so that any module (a pure-math one
included) can raise them without loading an image library or the config machinery:

- :class:`InputError`: bad user input (a file, an image, a config value); the message names the file or the
  config key and says what to do. :mod:`natscene.runner` turns it into one clear line and exit status 1.
- :class:`ConfigError`: the config is invalid (schema, cross-references, memory); the message names the key
  path. Raised before any job starts (:mod:`natscene.config`, :mod:`natscene.config_checks`).
"""
from __future__ import annotations

__all__ = ["InputError", "ConfigError"]


class InputError(ValueError):
    """Bad user input (file, image, config value); the message names it and says what to do."""


class ConfigError(ValueError):
    """The config is invalid; the message names the key path."""
