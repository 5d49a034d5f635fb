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
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import casadi as ca
import numpy as np

COMPILER = os.environ.get("CC", "gcc")
# -O1: most of the speed for a short build. An NLP solver's function whose C is over
# O0_SOURCE_BYTES is built at -O0 instead: gcc's time at -O1 grows faster than the
# function's size, and a solve is a few % slower. The anytime SQP's functions (`function`,
# `functions`) stay at -O1: at -O0 its re-plans did less within their CPU budget and missed
# the threshold (docs/realtime.md, 'planning.formulation.compiled')
FLAGS = ("-O1", "-fPIC")
O0_SOURCE_BYTES = 500_000
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


def _shared_library(functions: list[ca.Function], what: str, quick: bool = False
                    ) -> Path | None:
    """One shared library exporting each of functions under its name (cached by the hash of
    their C and the build's flags); each function's C is a unit of its own, the units built in
    parallel (quick: -O0 for a unit over O0_SOURCE_BYTES). None if their C is over
    MAX_SOURCE_BYTES in all."""

    def _flags(size: int) -> tuple[str, ...]:
        return ("-O0", *FLAGS[1:]) if quick and size > O0_SOURCE_BYTES else FLAGS

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
        key = hashlib.sha256()
        for text in texts:
            key.update(text + " ".join((COMPILER, *_flags(len(text)))).encode())
        key.update(ca.__version__.encode())
        target = folder / f"{key.hexdigest()[:20]}.so"
        if not target.exists():
            log.info("compiling %s (%d kB of C)", what, sum(map(len, texts)) // 1000)
            objects = [source.with_suffix(".o") for source in sources]
            # largest first: the longest build starts at once
            order = sorted(range(len(sources)), key=lambda i: -len(texts[i]))
            with ThreadPoolExecutor(max_workers=min(len(sources), os.cpu_count() or 1)) as pool:
                list(pool.map(lambda i: _run([COMPILER, *_flags(len(texts[i])), "-c",
                                              str(sources[i]), "-o", str(objects[i])]), order))
            log.debug("built %s", ", ".join(f"{f.name()} {len(t) // 1000} kB"
                                            for f, t in zip(functions, texts, strict=True)))
            built = Path(tmp) / "library.so"
            _run([COMPILER, "-shared", *map(str, objects), "-o", str(built), "-lm"])
            os.replace(built, target)
    return target


def _run(command: list[str]) -> None:
    subprocess.run(command, check=True, capture_output=True)


def library(solver: ca.Function) -> Path | None:
    """The compiled shared library of `solver`'s NLP functions (built on first need); None if
    their C source is over MAX_SOURCE_BYTES (too long to build: they stay interpreted)."""
    if not available():
        raise CompilerMissing(f"C compiler '{COMPILER}' not found")
    functions = [solver.oracle()] + [solver.get_function(name) for name in solver.get_function()]
    return _shared_library(functions, "the planning problem", quick=True)


def function(f: ca.Function) -> ca.Function:
    """f compiled to C (cached like the NLPs' libraries) and loaded back; f itself where no
    C compiler is found or its source is over MAX_SOURCE_BYTES."""
    if not available():
        return f
    target = _shared_library([f], f.name())
    return f if target is None else ca.external(f.name(), str(target))


def functions(fs: list[ca.Function]) -> list[ca.Function]:
    """Each of fs compiled to C as `function` does, in one library (their units built in
    parallel)."""
    if not available():
        return list(fs)
    target = _shared_library(list(fs), ", ".join(f.name() for f in fs))
    return list(fs) if target is None else [ca.external(f.name(), str(target)) for f in fs]


def nlpsol(name: str, plugin: str, problem: dict, options: dict) -> ca.Function:
    """ca.nlpsol on `problem` (x, p, f, g) with its functions compiled (cached), or evaluated
    in CasADi's virtual machine where they are too large to compile (see library)."""
    generator = ca.nlpsol(f"{name}_source", plugin, problem, options)
    built = library(generator)
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
