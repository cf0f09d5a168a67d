"""How the kernels are compiled and cached: each on its own, and never from stale sources.

numba's ``njit`` links every jitted callee into its caller's machine code and optimises the whole
call tree again for each caller, so a kernel deep in the step loop (a drag row, say) was optimised
some ten times, once for every function above it; a cold start took a minute.  Here every kernel is
compiled, optimised and cached once, as a function of its own, and its callers call it by name:

* ``KernelDispatcher`` is numba's CPU dispatcher whose calls from other kernels are typed as
  ``SeparateCall``.  Lowering such a call declares the callee under a stable name (module, name and
  a digest of its argument types) and calls it with numba's calling convention (errors propagate
  as usual), instead of linking the callee's code in.  The name is bound to the address of the
  callee's compiled code with ``llvmlite.binding.add_symbol``, as ``lapack.py`` binds LAPACK's
  routines; a caller loaded from the cache first binds its callees again (numba's ``reload_init``),
  compiling or loading each from its own cache.
* ``KernelCache`` is numba's function cache with one change: a kernel's cache is valid only for the
  sources of the whole kernel package (a digest of every ``.py`` file under ``wetcloth/kernels``),
  not just of its own file.  numba's own check sees only the file that defines a function, so a
  caller would have kept running the machine code of an edited callee or constant from another
  file; now any change to any kernel source makes every cached kernel recompile.

A kernel declared ``inline="always"`` is inlined by numba into its callers (no call at all) and stays
an ordinary numba dispatcher, with the same cache rule.  Calls between kernels cost a function call
each (tens of nanoseconds); every call in the step loop does work on whole arrays.

Measured (``bench/compile_time.py``): the first run of a 9 x 9 towel in a new process with an empty
cache takes 17 s of CPU instead of 66 s; loading from the cache is as quick as before.

**numba internals this relies on** (present from numba 0.63, which first keeps ``_reload_init`` on
the code library, to numba's main branch of 2026-08; ``tests/test_kernel_cache.py`` fails if one of
them changes):

* ``numba.core.caching``: ``FunctionCache._impl_class``, ``CompileResultCacheImpl._locator_classes``,
  ``get_filename_base``, the locators ``UserProvidedCacheLocator``, ``InTreeCacheLocator``,
  ``UserWideCacheLocator`` (public names from 0.62), their ``_py_file`` and ``get_source_stamp``;
* ``CPUDispatcher(py_func, locals, targetoptions)``, its ``overloads``, ``enable_caching`` and
  ``_numba_type_``; the typing context's ``_remove_global`` and ``insert_global``; the target
  options ``no_cpython_wrapper``, ``no_cfunc_wrapper`` and ``_nrt`` (``wetcloth.kernels``);
* ``types.Dispatcher.get_impl_key`` (its result keys the lowering), the target context's
  ``insert_func_defn``, ``call_conv.get_function_type`` / ``call_function`` /
  ``return_status_propagate``, ``active_code_library._reload_init`` (callables run before a cached
  library is linked); a compile result's ``library.get_pointer_to_function`` and
  ``fndesc.llvm_func_name``.
"""

from __future__ import annotations

import functools
import hashlib
import importlib
import sys
from pathlib import Path

import llvmlite.binding
import numba

#: The oldest numba with every internal listed in the module's docstring (checked before they are
#: imported: an FMU's host Python brings its own numba, which no installer checked).
OLDEST_NUMBA = (0, 63)
if tuple(int(part) for part in numba.__version__.split(".")[:2]) < OLDEST_NUMBA:
    raise ImportError(f"wetcloth needs numba >= 0.63; this Python ({sys.executable}) has numba {numba.__version__}: "
                      f"{sys.executable} -m pip install 'numba>=0.63'")

from numba.core import cgutils, types  # noqa: E402
from numba.core.caching import (CompileResultCacheImpl, FunctionCache, InTreeCacheLocator,  # noqa: E402
                                UserProvidedCacheLocator, UserWideCacheLocator)
from numba.core.datamodel.models import OpaqueModel, register_default  # noqa: E402
from numba.core.imputils import impl_ret_new_ref  # noqa: E402
from numba.core.registry import CPUDispatcher, cpu_target  # noqa: E402

#: The kernel package: a kernel defined under it is cached against the digest of all of it.
KERNELS = Path(__file__).resolve().parent


# ----------------------------------------------------------------------------------- the cache rule
@functools.lru_cache(maxsize=None)
def sources_digest(folder: Path) -> str:
    """SHA-256 of every ``.py`` file under ``folder`` (names and contents, in sorted order)."""
    digest = hashlib.sha256()
    for path in sorted(folder.rglob("*.py")):
        digest.update(path.relative_to(folder).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


def _scope(py_file: str) -> Path:
    """The folder whose sources a function's compiled code depends on: the kernel package for a
    kernel, else the function's own folder."""
    path = Path(py_file).resolve()
    return KERNELS if KERNELS in path.parents else path.parent


class _PackageStamp:
    """A locator whose source stamp is the digest of the function's package, not of its file alone."""

    def get_source_stamp(self):
        return sources_digest(_scope(self._py_file))


class _UserProvidedLocator(_PackageStamp, UserProvidedCacheLocator):
    pass


class _InTreeLocator(_PackageStamp, InTreeCacheLocator):
    pass


class _UserWideLocator(_PackageStamp, UserWideCacheLocator):
    pass


class _KernelCacheImpl(CompileResultCacheImpl):
    _locator_classes = [_UserProvidedLocator, _InTreeLocator, _UserWideLocator]


class KernelCache(FunctionCache):
    """numba's function cache (same places: ``NUMBA_CACHE_DIR``, ``__pycache__``, the user's cache),
    valid only for the sources it was compiled from (see the module's docstring)."""

    _impl_class = _KernelCacheImpl


# ----------------------------------------------------------------------------------- separate calls
def _symbol(dispatcher, argtypes) -> str:
    """The stable name a compiled specialisation is called by."""
    function = dispatcher.py_func
    digest = hashlib.sha256(repr(tuple(str(t) for t in argtypes)).encode()).hexdigest()[:20]
    return f"wetcloth.kernel.{function.__module__}.{function.__qualname__}.{digest}"


def bind(module: str, qualname: str, argtypes: tuple) -> str:
    """Compile (or load from the cache) kernel ``module.qualname`` for ``argtypes`` and bind its name
    to its machine code in this process; return the name.  Also run when a caller is loaded from the
    cache, before its code is linked."""
    dispatcher = importlib.import_module(module)
    for part in qualname.split("."):
        dispatcher = getattr(dispatcher, part)
    dispatcher = dispatcher.callee
    compiled = dispatcher.overloads.get(argtypes)
    if compiled is None:
        dispatcher.compile(argtypes)
        compiled = dispatcher.overloads[argtypes]
    address = compiled.library.get_pointer_to_function(compiled.fndesc.llvm_func_name)
    if not address:
        raise RuntimeError(f"kernel {module}.{qualname}{argtypes}: no machine code to bind")
    symbol = _symbol(dispatcher, argtypes)
    llvmlite.binding.add_symbol(symbol, address)
    return symbol


_lowered = set()  # implementation keys whose lowering is registered in this process


class SeparateCall(types.Dispatcher):
    """The type of a ``KernelDispatcher`` inside other kernels: typed like numba's dispatchers (the
    callee is compiled for the call's argument types), lowered as a call by name (no linking)."""

    def get_impl_key(self, sig):
        dispatcher = self.dispatcher
        argtypes = tuple(sig.args)
        key = ("wetcloth.kernel", _symbol(dispatcher, argtypes))
        if key in _lowered:
            return key
        function = dispatcher.py_func
        rebind = functools.partial(bind, function.__module__, function.__qualname__, argtypes)
        symbol = rebind()

        def call(context, builder, signature, args):
            callee = cgutils.get_or_insert_function(
                builder.module, context.call_conv.get_function_type(signature.return_type, signature.args), symbol)
            status, result = context.call_conv.call_function(builder, callee, signature.return_type, signature.args,
                                                             args)
            with cgutils.if_unlikely(builder, status.is_error):
                context.call_conv.return_status_propagate(builder, status)
            context.active_code_library._reload_init.add(rebind)  # a cached caller binds its callee first
            return impl_ret_new_ref(context, builder, signature.return_type, result)

        cpu_target.target_context.insert_func_defn([(call, key, argtypes)])
        _lowered.add(key)
        return key


register_default(SeparateCall)(OpaqueModel)


class _Cached(CPUDispatcher):
    """numba's CPU dispatcher with numba's checks (``nopython``, no bounds checks), cached by ``KernelCache``."""

    cache_class = KernelCache

    def __init__(self, py_func, targetoptions: dict):
        super().__init__(py_func=py_func, locals={}, targetoptions=dict(targetoptions, nopython=True, boundscheck=None))

    def enable_caching(self):
        self._cache = self.cache_class(self.py_func)


class _CalleeCacheImpl(_KernelCacheImpl):
    def get_filename_base(self, fullname, abiflags):
        return super().get_filename_base(fullname + ".callee", abiflags)


class _CalleeCache(KernelCache):
    _impl_class = _CalleeCacheImpl


class _Callee(_Cached):
    """A kernel as other kernels call it: machine code only, without the wrappers that convert
    Python objects (which, for the bundles of arrays the step loop passes around, cost ten times
    the compile time of a small kernel itself).  Cached in files of its own."""

    cache_class = _CalleeCache

    def __init__(self, py_func, targetoptions: dict):
        super().__init__(py_func, dict(targetoptions, no_cpython_wrapper=True, no_cfunc_wrapper=True))


class KernelDispatcher(_Cached):
    """A kernel: called from Python, it compiles as numba's dispatchers do (with the wrapper that
    takes Python objects); called from other kernels, it is ``callee`` (no wrappers), called by name."""

    def __init__(self, py_func, targetoptions: dict):
        super().__init__(py_func, targetoptions)
        self.callee = _Callee(py_func, targetoptions)
        self.typingctx._remove_global(self)
        self._type = SeparateCall(self.callee)
        self.typingctx.insert_global(self, self._type)

    @property
    def _numba_type_(self):
        return self._type

    def enable_caching(self):
        super().enable_caching()
        self.callee.enable_caching()


def compile_kernel(function, options: dict):
    """``function`` as a kernel with numba's ``options`` (``cache=True``: cached by ``KernelCache``)."""
    options = dict(options)
    cache = options.pop("cache", False)
    kind = _Cached if options.get("inline") == "always" else KernelDispatcher
    dispatcher = kind(function, options)
    if cache:
        dispatcher.enable_caching()
    return dispatcher


class TypedCall:
    """A kernel called from Python again and again with the same objects: its compiled code is
    looked up once for their types, not on every call.

    numba's dispatcher types every argument at each call; for the step loop's bundles of some sixty
    arrays that costs 87 us (on an idle machine; 187 us loaded), a tenth of a towel's frame, where a
    whole ``Simulation.advance`` call that takes no step costs 8 us through this
    (``bench/call_overhead.py``).  An argument that is the very object of the last call is not typed
    again (the objects are held, so none of them can be replaced by another at the same address);
    another object is typed, and the compiled code is found again only if its type differs (or a
    number changes its Python type): a new array of the same kind costs about a microsecond.
    Uses the dispatcher's ``overloads`` and ``typeof_pyval`` and a compile result's ``entry_point``.
    """

    def __init__(self, dispatcher):
        self._dispatcher = dispatcher
        self._arguments: tuple = ()
        self._types: tuple = ()
        self._entry_point = None

    def __call__(self, *args):
        if not self._same_types(args):
            self._types = tuple(self._dispatcher.typeof_pyval(a) for a in args)
            if self._types not in self._dispatcher.overloads:
                self._dispatcher.compile(self._types)  # (or loads it from the cache)
            self._entry_point = self._dispatcher.overloads[self._types].entry_point
        self._arguments = args
        return self._entry_point(*args)

    def _same_types(self, args) -> bool:
        held = self._arguments
        if len(held) != len(args) or self._entry_point is None:
            return False
        for old, new, known in zip(held, args, self._types):
            if new is old:
                continue
            if isinstance(new, (bool, int, float)):
                if type(old) is not type(new):
                    return False
            elif self._dispatcher.typeof_pyval(new) != known:
                return False
        return True
