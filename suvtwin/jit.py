"""numba compilation with an on-disk cache that knows what was compiled into each function.

Usual call::

    @cached_njit
    def step(x, p):
        return vertical_force(x, p) + GRAVITY   # a compiled function and a constant of other modules

``numba.njit(cache=True)`` keys its cache on the function's own source file (modification
time and size) and bytecode. It compiles into the machine code, by value, every compiled
function the body calls and every global number, string, tuple or array it reads; when
one of those lives in another module and changes, numba still loads the old machine code
(a stale kernel). :func:`cached_njit` adds to numba's key a digest of exactly those inputs,
found by walking the function's globals: each compiled callee's bytecode, constants and
names and compile options (and, recursively, its own inputs) and the value of each global
constant. A change
anywhere in that set gives a new key, so numba compiles afresh; the old entry is never
loaded again (nothing is deleted; numba drops the whole index itself when the function's
own file changes).

The digest is computed when numba looks an entry up (first call in a process), from the
objects in memory, so it sees what will be compiled, whatever file they came from.
"""

from __future__ import annotations

import hashlib
import types
from collections.abc import Callable

import numba
import numpy as np
from numba.core.caching import FunctionCache
from numba.core.dispatcher import Dispatcher

__all__ = ["cached_njit", "compiled_inputs"]

_SCALARS = (bool, int, float, complex, str, bytes, type(None))


def _is_compiled(value: object) -> bool:
    return isinstance(value, Dispatcher)


def _constant_text(value: object) -> str | None:
    """How numba would freeze `value` as a compile-time constant, as text; None if it does not."""
    if isinstance(value, _SCALARS):
        return f"{type(value).__name__}:{value!r}"
    if isinstance(value, tuple) and all(isinstance(v, _SCALARS) for v in value):
        return f"tuple:{value!r}"
    if isinstance(value, np.ndarray):
        digest = hashlib.sha256(np.ascontiguousarray(value).tobytes()).hexdigest()
        return f"ndarray:{value.dtype.str}:{value.shape}:{digest}"
    if isinstance(value, np.generic):
        return f"{value.dtype.str}:{value.item()!r}"
    return None


def _const_text(const: object) -> str:
    """repr of a code object's constant, the same in every process (set order varies with hashing)."""
    if isinstance(const, frozenset):
        return "frozenset(" + ",".join(sorted(_const_text(c) for c in const)) + ")"
    if isinstance(const, tuple):
        return "(" + ",".join(_const_text(c) for c in const) + ")"
    return repr(const)


def _code_objects(code: types.CodeType):
    yield code
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            yield from _code_objects(const)


def compiled_inputs(func: Callable) -> dict[str, str]:
    """Everything numba compiles into `func` (a compiled function or a plain one), by name.

    Keys: ``module.qualname`` of `func` and of each compiled function it reaches through
    its globals (value: digest of bytecode, constants and names), and
    ``module.qualname:NAME`` for each global constant one of them reads (value: the
    constant as text). Attributes read from a global module (``vehicle.GRAVITY``) count too.
    Plain Python functions of `func`'s own top-level package that it reaches are followed
    as well (numba compiles them in when they are ``register_jitable`` or overloaded).
    """
    inputs: dict[str, str] = {}
    root = getattr(func, "py_func", func)
    package = root.__module__.split(".")[0]
    todo = [root]
    while todo:
        f = todo.pop()
        where = f"{f.__module__}.{f.__qualname__}"
        if where in inputs:
            continue
        h = hashlib.sha256()
        names: set[str] = set()
        for code in _code_objects(f.__code__):
            h.update(code.co_code)
            consts = tuple(c for c in code.co_consts if not isinstance(c, types.CodeType))
            h.update(_const_text(consts).encode())
            h.update(repr((code.co_names, code.co_varnames, code.co_freevars)).encode())
            names.update(code.co_names)
        h.update(repr(f.__defaults__).encode())
        inputs[where] = h.hexdigest()
        found = {name: f.__globals__[name] for name in names if name in f.__globals__}
        for module in [v for v in found.values() if isinstance(v, types.ModuleType)]:
            for name in names:
                value = getattr(module, name, None)
                if _is_compiled(value) or isinstance(value, types.FunctionType) or (
                    value is not None and _constant_text(value) is not None
                ):
                    found[f"{module.__name__}.{name}"] = value
        for name, value in sorted(found.items()):
            if _is_compiled(value):
                todo.append(value.py_func)
                # its options (error_model, fastmath, ...) shape the machine code too
                inputs[f"{where}:{name}:options"] = repr(sorted(value.targetoptions.items()))
            elif isinstance(value, types.FunctionType) and value.__module__.split(".")[0] == package:
                todo.append(value)
            elif (text := _constant_text(value)) is not None:
                inputs[f"{where}:{name}"] = text
    return inputs


class _InputKeyedCache(FunctionCache):
    """numba's per-function cache, its index key extended by the digest of :func:`compiled_inputs`."""

    def _index_key(self, sig, codegen):
        inputs = compiled_inputs(self._py_func)
        digest = hashlib.sha256(repr(sorted(inputs.items())).encode()).hexdigest()
        return (*super()._index_key(sig, codegen), digest)


def cached_njit(func: Callable | None = None, **options):
    """``numba.njit(cache=True, **options)`` whose cache entries are also keyed on :func:`compiled_inputs`.

    Use it bare (``@cached_njit``) or with numba options (``@cached_njit(fastmath=False)``).
    """

    def wrap(f: Callable):
        dispatcher = numba.njit(cache=True, **options)(f)
        dispatcher._cache = _InputKeyedCache(dispatcher.py_func)  # numba's enable_caching, our key
        return dispatcher

    return wrap if func is None else wrap(func)
