"""Finding, importing, constructing and validating a processor named by a spec string."""

from __future__ import annotations

import ast
import contextlib
import difflib
import hashlib
import importlib
import importlib.util
import inspect
import pkgutil
import sys
import traceback
from dataclasses import dataclass, field
from importlib.metadata import entry_points
from pathlib import Path
from types import ModuleType
from typing import Any

from processors.base import ProcessorInfo, validate_processor
from processors.errors import ProcessorLoadError

ENTRY_POINT_GROUP = "uav_tui.processors"
"""Installed packages register processors here: ``name = "package.module:Class"``."""


@dataclass
class LoadedProcessor:
    """A constructed, validated processor and how to load it again."""

    instance: Any
    info: ProcessorInfo
    spec: str
    kwargs: dict[str, Any] = field(default_factory=dict)


def load(spec: str, builtins: dict[str, str], kwargs: dict[str, Any] | None = None, *,
         fresh: bool = False) -> LoadedProcessor:
    """Load ``spec``: a short name, an entry-point name, ``module:Class`` or ``path/file.py:Class``.

    ``fresh=True`` re-imports the code (for reloading an edited file without restarting).
    """
    kwargs = dict(kwargs or {})
    target = builtins.get(spec) or _entry_point_target(spec) or spec
    location, sep, class_name = target.rpartition(":")
    if not sep and target.endswith(".py"):
        raise _file_without_class(Path(target).expanduser(), target)
    if not sep or not location or not class_name:
        known = ", ".join(sorted(builtins))
        raise ProcessorLoadError(
            f"processor {spec!r} is not a known name ({known}) and not of the form module:Class or path/file.py:Class",
            class_name=class_name or None,
        )
    path: str | None
    if location.endswith(".py") or "/" in location or location.startswith("~"):
        module, path = _import_file(Path(location).expanduser(), class_name, fresh)
    else:
        module, path = _import_module(location, class_name, fresh)
    cls = getattr(module, class_name, None)
    if not isinstance(cls, type):
        defined = sorted(name for name, value in vars(module).items()
                         if isinstance(value, type) and value.__module__ == module.__name__)
        raise ProcessorLoadError(
            f"{path or location} has no class {class_name}; classes defined there: {', '.join(defined) or 'none'}",
            path=path, class_name=class_name, missing=class_name,
        )
    _check_arguments(cls, kwargs, path or location)
    try:
        instance = cls(**kwargs)
    except Exception as exc:
        raise ProcessorLoadError(f"{class_name}({_kwargs_text(kwargs)}) raised while constructing: "
                                 f"{_describe(exc, path)}", path=path, class_name=class_name) from exc
    info = validate_processor(instance, name=f"{location}:{class_name}", path=path)
    return LoadedProcessor(instance=instance, info=info, spec=spec, kwargs=kwargs)


def _file_without_class(path: Path, spec: str) -> ProcessorLoadError:
    """``--processor bright.py``: name the classes in the file that could be meant (read, not run)."""
    try:
        tree = ast.parse(path.read_text(), filename=str(path))
    except (OSError, SyntaxError, ValueError):
        return ProcessorLoadError(f"processor {spec!r} names a file but no class: give path/file.py:Class",
                                  path=str(path))
    candidates = [node.name for node in tree.body if isinstance(node, ast.ClassDef)
                  and any(isinstance(item, ast.FunctionDef | ast.AsyncFunctionDef) and item.name == "photo_processing"
                          for item in node.body)]
    if not candidates:
        return ProcessorLoadError(f"processor {spec!r} names a file but no class, and {path} defines no class with "
                                  "photo_processing(frame)", path=str(path), missing="photo_processing")
    return ProcessorLoadError(f"processor {spec!r} names a file but no class: use "
                              f"{' or '.join(f'{spec}:{name}' for name in candidates)}", path=str(path))


def _check_arguments(cls: type, kwargs: dict[str, Any], where: str | None) -> None:
    """Reject constructor arguments ``cls`` does not take, listing those it does (before calling it)."""
    try:
        parameters = list(inspect.signature(cls).parameters.values())
    except (TypeError, ValueError):  # no signature to read (some extension types): let the call decide
        return
    needed = [p.name for p in parameters if p.default is inspect.Parameter.empty and p.name not in kwargs
              and p.kind in (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)]
    if needed:
        given = " ".join(f"--processor-arg {name}=..." for name in needed)
        raise ProcessorLoadError(f"{cls.__name__} ({where}) needs the constructor argument{'s' * (len(needed) > 1)} "
                                 f"{', '.join(needed)}: give {given} (or [processor_args] in uav.toml)",
                                 path=where, class_name=cls.__name__, missing=needed[0])
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters):
        return
    accepted = [p.name for p in parameters if p.kind in (inspect.Parameter.POSITIONAL_OR_KEYWORD,
                                                         inspect.Parameter.KEYWORD_ONLY)]
    for key in kwargs:
        if key not in accepted:
            close = difflib.get_close_matches(key, accepted, n=1)
            hint = f"did you mean {close[0]!r}? " if close else ""
            takes = f"it takes {', '.join(accepted)}" if accepted else "it takes no arguments"
            raise ProcessorLoadError(f"{cls.__name__} ({where}) has no constructor argument {key!r} "
                                     f"(--processor-arg / [processor_args]); {hint}{takes}",
                                     path=where, class_name=cls.__name__, missing=key)
    by_name = {p.name: p for p in parameters}
    for key, value in kwargs.items():
        if key in by_name and (expected := _expected_kinds(by_name[key])) and not _fits(value, expected):
            kind = " or ".join(_KIND_WORDS[name] for name in expected)
            raise ProcessorLoadError(f"{cls.__name__} ({where}): constructor argument {key} must be {kind}, got "
                                     f"{type(value).__name__} {value!r:.60} (--processor-arg {key}=... is read as "
                                     "TOML: 0.5, 3, true, \"text\")", path=where, class_name=cls.__name__,
                                     missing=key)


_KINDS: dict[str, tuple[type, ...]] = {"float": (int, float), "int": (int,), "bool": (bool,), "str": (str,),
                                       "None": (type(None),)}
"""The plain types a constructor argument is checked against (the rest is left to the constructor)."""
_KIND_WORDS = {"float": "a number (float)", "int": "a whole number (int)", "bool": "true or false (bool)",
               "str": "text (str, in quotes)", "None": "None"}


def _expected_kinds(parameter: inspect.Parameter) -> tuple[str, ...]:
    """The plain type names a parameter takes, from its annotation (``float``, ``int | None``, as written or
    evaluated) or, without one, its default's type (an int default takes a float too); () when it says nothing
    plain."""
    annotation = parameter.annotation
    if annotation is inspect.Parameter.empty:
        default = type(parameter.default).__name__
        return ("float",) if default in ("int", "float") else (default,) if default in ("bool", "str") else ()
    text = annotation if isinstance(annotation, str) else getattr(annotation, "__name__", str(annotation))
    names = tuple(name.strip() for name in text.replace("NoneType", "None").split("|"))
    return names if all(name in _KINDS for name in names) else ()


def _fits(value: Any, kinds: tuple[str, ...]) -> bool:
    if isinstance(value, bool):  # an int to Python, a switch to the researcher
        return "bool" in kinds
    return any(isinstance(value, _KINDS[name]) for name in kinds)


def _entry_point_target(name: str) -> str | None:
    for entry in entry_points(group=ENTRY_POINT_GROUP, name=name):
        return entry.value
    return None


def _import_module(name: str, class_name: str, fresh: bool) -> tuple[ModuleType, str | None]:
    try:
        module = importlib.import_module(name)
        if fresh:
            module = importlib.reload(module)
    except ModuleNotFoundError as exc:
        if exc.name == name or name.startswith(f"{exc.name}."):
            raise ProcessorLoadError(f"no module named {name!r} (for class {class_name}); is it installed or on "
                                     "PYTHONPATH? For a file, give its path: path/to/file.py:Class",
                                     class_name=class_name, missing=name) from exc
        raise _import_error(exc, None, class_name) from exc
    except Exception as exc:
        raise _import_error(exc, None, class_name) from exc
    return module, getattr(module, "__file__", None)


def _import_file(path: Path, class_name: str, fresh: bool) -> tuple[ModuleType, str]:
    if not path.is_file():
        raise ProcessorLoadError(f"processor file {path} does not exist (working directory: {Path.cwd()})",
                                 path=str(path), class_name=class_name, missing=str(path))
    resolved = path.resolve()
    module_name = f"uav_tui_user_{resolved.stem}_{hashlib.sha1(str(resolved).encode()).hexdigest()[:8]}"
    if not fresh and module_name in sys.modules:
        return sys.modules[module_name], str(resolved)
    spec = importlib.util.spec_from_file_location(module_name, resolved)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    # The file's own folder first, so a researcher's helper modules beside it import.
    sys.path.insert(0, str(resolved.parent))
    try:
        spec.loader.exec_module(module)
    except Exception as exc:
        raise _import_error(exc, str(resolved), class_name) from exc
    finally:
        sys.path.remove(str(resolved.parent))
    sys.modules[module_name] = module
    return module, str(resolved)


def _import_error(exc: BaseException, path: str | None, class_name: str) -> ProcessorLoadError:
    missing = exc.name if isinstance(exc, ModuleNotFoundError) else None
    hint = f"; {_install_hint(missing)}" if missing else ""
    return ProcessorLoadError(f"importing {path or 'the processor module'} for {class_name} failed: "
                              f"{_describe(exc, path)}{hint}", path=path, class_name=class_name, missing=missing)


PIP_NAMES = {"cv2": "opencv-python", "sklearn": "scikit-learn", "skimage": "scikit-image", "PIL": "pillow",
             "yaml": "pyyaml", "serial": "pyserial"}
"""Modules whose package on PyPI has another name."""


def _install_hint(missing: str) -> str:
    """What to do about ``import missing`` failing: the installed module it is a typo of, or the command that installs
    it into the Python uav-tui runs on (its venv: a plain ``pip`` may be another Python's)."""
    top = missing.partition(".")[0]
    installed = sorted({module.name for module in pkgutil.iter_modules()} | set(sys.builtin_module_names))
    close = [name for name in difflib.get_close_matches(top, installed, n=1, cutoff=0.8) if name != top]
    if close:
        return f"no module {top!r} is installed, but {close[0]!r} is: is the import misspelt?"
    python = Path(sys.executable)
    with contextlib.suppress(ValueError):
        python = python.relative_to(Path.cwd())
    return f"install it into uav-tui's Python: {python} -m pip install {PIP_NAMES.get(top, top)}"


def _describe(exc: BaseException, path: str | None) -> str:
    """``file:line: Type: message`` for the deepest frame in the researcher's code (or the last one)."""
    if isinstance(exc, SyntaxError):
        return f"{exc.filename}:{exc.lineno}: SyntaxError: {exc.msg}"
    frames = traceback.extract_tb(exc.__traceback__)
    own = [f for f in frames if path and f.filename == path] or [f for f in frames if "importlib" not in f.filename]
    where = f"{own[-1].filename}:{own[-1].lineno}: " if own else ""
    return f"{where}{type(exc).__name__}: {exc}"


def _kwargs_text(kwargs: dict[str, Any]) -> str:
    return ", ".join(f"{key}={value!r}" for key, value in kwargs.items())
