"""NLP functions compiled to machine code with the system C compiler, cached per problem.

CasADi evaluates SX functions in a virtual machine; the same functions as C code,
compiled once, evaluate several times faster
(docs/realtime.md, 'planning.formulation.compiled'). Each function a solver instance needs
(its oracle and the derivatives it asks for) is written as C of its own, the texts are
hashed (with the compiler and its flags), and one shared library of them is built once,
the units in parallel, into a user cache directory
($TORQUEBENCH_CACHE, else $XDG_CACHE_HOME/torquebench, else ~/.cache/torquebench);
`nlpsol(name, plugin, library)` then loads it. Builds are atomic (a temporary name,
then a rename), so concurrent processes never load a half-written library.
"""

from __future__ import annotations

import hashlib
import logging
import os
import shutil
import subprocess
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import casadi as ca
import numpy as np

from planning.formulation import c_units

COMPILER = os.environ.get("CC", "gcc")
# -O1: most of the speed for a short build. An NLP solver's function whose C is over
# O0_SOURCE_BYTES is built at -O0 instead: gcc's time at -O1 grows faster than the
# function's size, and a solve is a few % slower. The anytime SQP's functions (`function`,
# `functions`) stay at -O1: at -O0 they run ~2.4x slower, and real-time re-plans do less
# within their CPU budget (docs/realtime.md, 'planning.formulation.compiled')
FLAGS = ("-O1", "-fPIC")
O0_SOURCE_BYTES = 500_000
# quick builds, for plans no CPU time decides: every unit at -O0, a function's C over
# PART_BYTES split into units of about that size (planning.formulation.c_units) built in
# parallel; the same operations in the same order, so the same bits, ~2.4x slower to run
# (docs/realtime.md, 'planning.formulation.compiled')
QUICK_FLAGS = ("-O0", "-fPIC")
PART_BYTES = 1_000_000
# Larger sources stay in CasADi's virtual machine: their build takes minutes and gigabytes
# (docs/realtime.md, 'planning.formulation.compiled')
MAX_SOURCE_BYTES = 8_000_000
log = logging.getLogger(__name__)  # a build is announced here (INFO): it can take a while


class CompilerMissing(RuntimeError):
    """No C compiler on this machine: the caller falls back to CasADi's virtual machine."""


def cache_dir() -> Path:
    """Where compiled NLP libraries are kept (created on demand)."""
    root = os.environ.get("TORQUEBENCH_CACHE")
    if root is None:
        base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
        root = Path(base) / "torquebench"
    path = Path(root) / "nlp"
    path.mkdir(parents=True, exist_ok=True)
    return path


def available() -> bool:
    """True if the C compiler can be found."""
    return shutil.which(COMPILER) is not None


def _shared_library(functions: list[ca.Function], what: str, nlp: bool = False,
                    quick: bool = False) -> Path | None:
    """One shared library exporting each of functions under its name (cached by the hash of
    their C and the build's flags); each function's C is a unit of its own, the units built in
    parallel at FLAGS (nlp: -O0 for a unit over O0_SOURCE_BYTES). quick: the library built so
    if cached, else every unit at QUICK_FLAGS. None if their C is over MAX_SOURCE_BYTES in all."""
    folder = cache_dir()
    with tempfile.TemporaryDirectory(dir=folder) as tmp:
        sources = []
        for f in functions:
            source = Path(tmp) / f"{f.name()}.c"
            generator = ca.CodeGenerator(source.name, {"with_header": False})
            generator.add(f)
            cwd = os.getcwd()
            os.chdir(tmp)  # the code generator writes into the working directory
            try:
                generator.generate()
            finally:
                os.chdir(cwd)
            sources.append(source)
        texts = [source.read_bytes() for source in sources]
        if sum(map(len, texts)) > MAX_SOURCE_BYTES:
            return None
        flags = [QUICK_FLAGS if nlp and len(text) > O0_SOURCE_BYTES else FLAGS
                 for text in texts]
        part_bytes = None
        target = folder / f"{_key(texts, flags)}.so"
        if quick and not target.exists():
            flags, part_bytes = [QUICK_FLAGS] * len(texts), PART_BYTES
            target = folder / f"{_key(texts, flags, part_bytes)}.so"
        if not target.exists():
            _build(sources, texts, flags, target, what, part_bytes)
    return target


def _key(texts: list[bytes], flags: list[tuple[str, ...]], part_bytes: int | None = None
         ) -> str:
    key = hashlib.sha256()
    for text, unit in zip(texts, flags, strict=True):
        key.update(text + " ".join((COMPILER, *unit)).encode())
    key.update(ca.__version__.encode())
    if part_bytes is not None:
        key.update(f"split into units of {part_bytes} bytes".encode())
    return key.hexdigest()[:20]


def _build(sources: list[Path], texts: list[bytes], flags: list[tuple[str, ...]],
           target: Path, what: str, part_bytes: int | None) -> None:
    """Compile each source with its flags (split into units of about part_bytes if given),
    the units in parallel, the largest first so that the longest build starts at once; link
    them and move the library to target."""
    kilobytes = sum(map(len, texts)) // 1000
    level = "/".join(sorted({unit[0] for unit in flags}))
    log.info("compiling %s (%d kB of C, %s)", what, kilobytes, level,
             extra={"stage": what, "kilobytes": kilobytes, "level": level, "done": False})
    began = time.perf_counter()
    units: list[tuple[Path, tuple[str, ...], int]] = []
    for source, text, unit_flags in zip(sources, texts, flags, strict=True):
        split = [text.decode()] if part_bytes is None else c_units.split(text.decode(),
                                                                         part_bytes)
        for k, code in enumerate(split):
            path = source if k == 0 else source.with_name(f"{source.stem}_unit{k}.c")
            path.write_text(code)
            units.append((path, unit_flags, len(code)))
    units.sort(key=lambda unit: -unit[2])
    objects = [path.with_suffix(".o") for path, _, _ in units]
    with ThreadPoolExecutor(max_workers=min(len(units), os.cpu_count() or 1)) as pool:
        list(pool.map(lambda unit, obj: _run([COMPILER, *unit[1], "-c", str(unit[0]), "-o",
                                              str(obj)]), units, objects))
    built = sources[0].parent / "library.so"
    _run([COMPILER, "-shared", *map(str, objects), "-o", str(built), "-lm"])
    os.replace(built, target)
    seconds = time.perf_counter() - began
    log.info("compiled %s in %.0f s", what, seconds,
             extra={"stage": what, "kilobytes": kilobytes, "level": level, "done": True})


def _run(command: list[str]) -> None:
    subprocess.run(command, check=True, capture_output=True)


def library(solver: ca.Function, quick: bool = False) -> Path | None:
    """The compiled shared library of `solver`'s NLP functions (built on first need; quick:
    as _shared_library); None if their C source is over MAX_SOURCE_BYTES (too long to build:
    they stay interpreted)."""
    if not available():
        raise CompilerMissing(f"C compiler '{COMPILER}' not found")
    functions = [solver.oracle()] + [solver.get_function(name) for name in solver.get_function()]
    return _shared_library(functions, "the NLP solvers' functions", nlp=True, quick=quick)


def function(f: ca.Function, quick: bool = False, what: str | None = None) -> ca.Function:
    """f compiled to C (cached like the NLPs' libraries; quick: as _shared_library; what:
    what its build is announced as) and loaded back; f itself where no C compiler is found
    or its source is over MAX_SOURCE_BYTES."""
    return functions([f], quick, what)[0]


def functions(fs: list[ca.Function], quick: bool = False, what: str | None = None
              ) -> list[ca.Function]:
    """Each of fs compiled to C as `function` does, in one library (their units built in
    parallel)."""
    if not available():
        return list(fs)
    target = _shared_library(list(fs), what or ", ".join(f.name() for f in fs), quick=quick)
    return list(fs) if target is None else [ca.external(f.name(), str(target)) for f in fs]


def nlpsol(name: str, plugin: str, problem: dict, options: dict, quick: bool = False
           ) -> ca.Function:
    """ca.nlpsol on `problem` (x, p, f, g) with its functions compiled (cached; quick: as
    _shared_library), or evaluated in CasADi's virtual machine where they are too large to
    compile (see library)."""
    generator = ca.nlpsol(f"{name}_source", plugin, problem, options)
    built = library(generator, quick)
    if built is None:
        return ca.nlpsol(name, plugin, problem, options)
    return ca.nlpsol(name, plugin, str(built), options)


class Buffered:
    """A function of numpy vectors evaluated through a CasADi buffer (a much cheaper call,
    no conversion of its outputs: docs/realtime.md, 'planning.formulation.compiled'):
    inputs are copied into its arguments, the output vector is its result."""

    def __init__(self, function: ca.Function):
        self.function = function
        self.args = [np.zeros(function.nnz_in(i)) for i in range(function.n_in())]
        self.out = [np.zeros(function.nnz_out(i)) for i in range(function.n_out())]
        self._buffer, self._evaluate = function.buffer()
        for i, arg in enumerate(self.args):
            self._buffer.set_arg(i, memoryview(arg))
        for i, res in enumerate(self.out):
            self._buffer.set_res(i, memoryview(res))

    def __call__(self, *args) -> list[np.ndarray]:
        for target, value in zip(self.args, args, strict=True):
            target[:] = value
        self._evaluate()
        return self.out
