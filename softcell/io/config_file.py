"""Run configurations from TOML files."""

from __future__ import annotations

import os
import tomllib
from pathlib import Path

from softcell.errors import ConfigError
from softcell.model.configuration import RunConfig, config_from_mapping


def load_config(path: str | os.PathLike[str]) -> RunConfig:
    """Read a TOML run configuration (tables ``[parameters]``, ``[components]``, ``[run]``).

    Raises
    ------
    ConfigError
        For a missing, unreadable or non-UTF-8 file, a directory, bad TOML, an unknown
        table or key (with a suggestion), or a value of the wrong type. Parameter values
        are validated later, by :class:`softcell.Parameters`.
    """
    return config_from_mapping(read_toml(path), path)


def read_toml(path: str | os.PathLike[str]) -> dict:
    """The tables of a TOML file.

    Raises
    ------
    ConfigError
        For a missing, unreadable or non-UTF-8 file, a directory, or bad TOML.
    """
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8-sig"))  # a BOM (Notepad) is no TOML
    except FileNotFoundError:
        raise ConfigError(f"no such configuration file: {path}") from None
    except IsADirectoryError:
        raise ConfigError(f"{path} is a directory, not a configuration file") from None
    except PermissionError:
        raise ConfigError(f"{path}: permission denied (the file is not readable)") from None
    except UnicodeDecodeError as exc:
        raise ConfigError(
            f"{path}: not a text file in UTF-8 (byte {exc.start}); TOML files are UTF-8"
        ) from None
    except OSError as exc:
        raise ConfigError(f"{path}: cannot be read ({exc.strerror or exc})") from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path}: not valid TOML: {exc}") from None
    return data
