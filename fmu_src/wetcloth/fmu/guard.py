"""Keep a unit and its host alive: fixes of pythonfmu's binaries (FMI 2.0 and 3.0), made at their Python seam.

1. pythonfmu and pythonfmu3 turn a Python exception in any slave method into an FMI Fatal status,
   the only way such a method can report an error (``fmi2SetReal``, ``fmi2ExitInitializationMode``,
   the FMU-state calls...).  On the way, their C++ ``handle_py_exception`` releases the instance's
   references to its Python objects (the slave, its class and its log queue) but keeps using the
   pointers: the next call on that instance used freed memory and the host crashed (seen: a
   ``doStep`` after two refused ``fmi2DeSerializeFMUstate``).  Each wrapped entry point gives those
   objects one reference back before the exception leaves Python.  An instance that has reported
   an error therefore stays in memory until the process ends (a bounded leak on error paths
   only), and every later call on it works.  The class-level state decoders
   (``_fmu_state_from_bytes``, ``_fmu_state_to_bytes``) cannot know which instance called them,
   so their errors do this for every live instance.
2. pythonfmu's ``findClass`` (FMI 2.0) runs the slave script again in the script module's
   namespace at every instantiation, then releases a reference to that namespace it never took
   (``Py_DECREF`` of ``PyModule_GetDict``'s borrowed result): after a few instances the namespace
   was freed while the module still used it.  The script calls ``hold_script_namespace(globals())``
   on every run, giving that reference back.
3. At process exit both binaries release their interpreter helper (``PyState``) twice: its static
   ``shared_ptr`` is destroyed by the exit handlers, then the library's destructor assigns to the
   destroyed pointer, which corrupted the heap ("corrupted double-linked list", exit status 134)
   in about one exit in two.  ``release_at_exit`` (in ``wetcloth.fmu.bootstrap``, so that it is in
   place before anything of the unit can fail, even a refused instantiation) has Python's own
   exit call the binary's ``finalizePythonInterpreter`` first, while the pointer is alive; the
   later calls then find it empty.  It also keeps every unit binary loaded until then: unloaded
   when its host frees the unit, a binary runs the same exit handlers at once.  Only in a Python
   host: where the binary started the interpreter itself, its exit path must run as written.

4. Both binaries hand the master the slave's Python object as the FMU state pointer and pass any
   pointer the master gives back to Python as that object, unchecked (``fmi2SetFMUstate``,
   ``fmi2SerializedFMUstateSize``...); ``fmi2FreeFMUstate`` only releases a reference and leaves the
   master's pointer as it was.  A freed state therefore was freed memory read as an object: the host
   crashed.  The unit hands out a ``StateHandle`` instead: freed by the master, it drops its
   checkpoint but is kept alive (with ``SPARE_FREES`` references to spare for a master that frees
   the same pointer again), and a handle is looked up by its address among those handed out before
   anything reads it, so that a freed, stray or foreign pointer is refused with an error.  Limits
   (the binaries' code, before Python runs): they add and remove one reference at the pointer
   itself, so a pointer into unmapped memory, or to memory whose first word is 0, still crashes;
   they cannot set the master's pointer to NULL at free as FMI 2.0 asks; every freed handle keeps
   a few hundred bytes until the process ends.

5. An instance the master never frees, or one kept alive by 1., still holds its simulation when Python exits;
   the compiled core's module then reports its objects as leaked ("nanobind: leaked 1 instances! ... Stepper").
   At exit every live instance drops its simulation (``_release_all``), so nothing of the core outlives it.

6. On an exception, both binaries' ``handle_py_exception`` flush the instance's log queue to the master's
   logger callback before they fetch the exception: the master's callback (Python code, in a Python host such
   as fmpy) then ran with an exception pending.  The exception was lost on the way (the master read "Fatal py
   exception encountered: ... unknown error"), and running Python code in that state is undefined.  Each
   wrapped entry point therefore empties its instance's queue before an exception leaves it, into the
   exception's own text, which the binary logs (the master reads one Fatal message with the reason, where it
   read an Error message and "unknown error").

7. Both binaries build ``set_string``'s list of texts with ``Py_BuildValue("s")``: a text that is not UTF-8
   leaves an empty slot (NULL) in the list, and the binary looks ``set_string`` up and calls it with that
   decoding error still pending.  With an error pending, CPython's attribute lookup is a matter of luck:
   a lookup that misses its type attribute cache fails in the first class of the instance's MRO that lacks
   the name, clearing the error as it goes.  The unit's ``__getattr__`` used to take the refusal from there,
   but a miss on ``__getattr__`` itself (whenever another lookup had taken its cache slot) made CPython drop
   the class's ``__getattr__`` hook for good and find the real ``set_string``, which read the empty slot:
   a segmentation fault in the host, now and then (a test's child master: 1 run in 10 to 30; every run when
   the class is changed just before the call, which empties its cache entries).
   ``set_string`` is now found in the class's own dict (``WetClothUnit.__init_subclass__``), before any
   failing lookup; it is a data descriptor (``TextSetter``), so that CPython reaches it before the
   instance's dict; its getter clears the pending error before anything else runs, and the method refuses
   a list with an empty slot before reading it.

The references given back in 1 and 2 are real reference counts (``Py_IncRef``), not objects held in
a list: the binary has already dropped them, and a list released at interpreter shutdown would
drop them a second time.
"""

from __future__ import annotations

import atexit
import ctypes
import functools
import gc
import inspect
import types
import weakref

_incref = ctypes.pythonapi.Py_IncRef
_incref.argtypes = [ctypes.py_object]
_incref.restype = None

#: Every slave instance alive in this process (for errors of the class-level decoders).
_LIVE: weakref.WeakSet = weakref.WeakSet()


def _give_back(instances) -> None:
    """One reference to each object the binary drops after an exception of ``instance`` (see 1.)."""
    for instance in instances:
        for obj in (instance, instance.log_queue, type(instance)):
            _incref(obj)


def hold_script_namespace(namespace: dict) -> None:
    """Give pythonfmu's ``findClass`` the reference to the slave script's namespace it releases (see 2.)."""
    _incref(namespace)


def register(instance) -> None:
    """Note a new slave instance (called from its ``__init__``)."""
    if not _LIVE and not _EXIT_HOOK:
        _EXIT_HOOK.append(atexit.register(_release_all))
    _LIVE.add(instance)


#: The exit hook, once registered.
_EXIT_HOOK: list = []


def _release_all() -> None:
    """At Python's exit, let every instance still alive drop its simulation (see 5.): instances kept alive by 1.,
    or never freed by their master, would otherwise hold the compiled core's objects past its module's end
    ("nanobind: leaked ... Stepper" at exit)."""
    for instance in list(_LIVE):
        release = getattr(instance, "release", None)
        if release is not None:
            try:
                release()
            except Exception:
                pass


def guard(cls, methods: tuple[str, ...], class_methods: tuple[str, ...]):
    """Wrap ``cls``'s entry points in place: ``methods`` are called on an instance,
    ``class_methods`` (static or class methods) on the class; returns ``cls``."""
    for name in methods:
        method = getattr(cls, name)
        if name == TEXT_SETTER:
            setattr(cls, name, TextSetter(_instance_entry(_refusing_empty_slots(method))))
        else:
            setattr(cls, name, _instance_entry(method))
    for name in class_methods:
        found = inspect.getattr_static(cls, name)
        if isinstance(found, classmethod):
            setattr(cls, name, classmethod(_class_entry(found.__func__)))
        else:
            setattr(cls, name, staticmethod(_class_entry(getattr(found, "__func__", found))))
    return cls


def _fold_queued_messages(instance, exc: BaseException) -> None:
    """Empty ``instance``'s log queue into the text of ``exc``, which the binary logs (see 6.): the queued
    messages in turn, then the exception's own text unless one of them already says it, joined by "; "."""
    queue = instance.log_queue
    held = [message.msg for message in queue if not getattr(message, "debug", False)]
    del queue[:]  # the binary's own reference to this list stays valid: emptied in place
    text = str(exc) if exc.args else ""
    if held:
        exc.args = ("; ".join(held + [text] if text and not any(text in message for message in held) else held),)


def _instance_entry(method):
    @functools.wraps(method)
    def entry(self, *args):
        try:
            return method(self, *args)
        except BaseException as exc:
            _give_back([self])
            _fold_queued_messages(self, exc)
            raise

    return entry


def _class_entry(function):
    @functools.wraps(function)
    def entry(*args):
        try:
            return function(*args)
        except BaseException:
            _give_back(list(_LIVE))
            raise

    return entry


# ------------------------------------------------------------------------------------ texts (see 7.)
#: The entry point through which both binaries set texts.
TEXT_SETTER = "set_string"


class _Settled(Exception):
    """Raised and caught at once: the exception that replaces a pending one (see 7.)."""


def _settle_pending_error() -> None:
    """Clear any exception the binary left pending: raising one replaces it, and catching that clears it.
    (Raising the class may itself fail with an error pending, as a SystemError: caught alike.)"""
    try:
        raise _Settled
    except BaseException:
        pass


def _empty_slots(values: list) -> int:
    """How many slots of ``values`` are empty (NULL, where the binary failed to decode a text), counted without
    reading them: the garbage collector's traversal of a list skips empty slots."""
    return len(values) - len(gc.get_referents(values))


def _refusing_empty_slots(method):
    @functools.wraps(method)
    def set_texts(self, vrs, values):
        if _empty_slots(values):
            self._refuse_undecodable_text(vrs)
        return method(self, vrs, values)

    return set_texts


class TextSetter:
    """``set_string`` as the binaries find it (see 7.): a data descriptor whose getter first clears the decoding
    error the binary may have left pending, then gives the guarded method bound to the instance."""

    __slots__ = ("method",)

    def __init__(self, method) -> None:
        self.method = method

    def __get__(self, instance, owner=None):
        _settle_pending_error()
        return self if instance is None else types.MethodType(self.method, instance)

    def __set__(self, instance, value) -> None:
        raise AttributeError(f"{TEXT_SETTER} is the unit's entry point; it cannot be replaced on an instance")


# ------------------------------------------------------------------------------------ FMU state handles
#: How many more times than once a master may free a state's handle before it is really freed (see 4.).
SPARE_FREES = 64
#: Handle address -> weak reference to the handle, for every handle handed out in this process.
_ISSUED: dict[int, weakref.ref] = {}


class StateHandle:
    """What a master holds as an FMU state (see 4.): the unit's checkpoint, or None once freed."""

    __slots__ = ("checkpoint", "__weakref__")

    def __init__(self, checkpoint) -> None:
        self.checkpoint = checkpoint
        _ISSUED[id(self)] = weakref.ref(self)

    def __del__(self) -> None:
        self.checkpoint = None  # the master freed it: drop the state, keep the few bytes of the handle
        for _ in range(1 + SPARE_FREES):
            _incref(self)


def handed_out(handle) -> object | None:
    """The checkpoint of ``handle`` if it is a live handle of this process, else None; the object is
    compared by address and identity only, never read, unless it is one of ours."""
    ref = _ISSUED.get(id(handle))
    if ref is None or ref() is not handle:
        return None
    return handle.checkpoint
