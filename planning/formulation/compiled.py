"""NLP functions compiled to machine code with the system C compiler, cached per problem.

CasADi evaluates SX functions in a virtual machine; the same functions as C code,
compiled once, evaluate several times faster
(docs/realtime.md, 'planning.formulation.compiled'). A solver instance writes the functions
it needs (`Function.generate_dependencies`), the C text is hashed (with the compiler and
its flags), and the shared library is built once into a user cache directory
($TORQUEBENCH_CACHE, else $XDG_CACHE_HOME/torquebench, else ~/.cache/torquebench);
`nlpsol(name, plugin, library)` then loads it. Builds are atomic (a temporary name,
then a rename), so concurrent processes never load a half-written library.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import casadi as ca
import numpy as np

COMPILER = os.environ.get("CC", "gcc")
# -O1: most of the speed for a short build (docs/realtime.md, 'planning.formulation.compiled')
FLAGS = ("-O1", "-fPIC", "-shared")
# Larger sources stay in CasADi's virtual machine: their build takes minutes and gigabytes
# (docs/realtime.md, 'planning.formulation.compiled')
MAX_SOURCE_BYTES = 8_000_000


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


def library(solver: ca.Function) -> Path | None:
    """The compiled shared library of `solver`'s NLP functions (built on first need); None if
    their C source is over MAX_SOURCE_BYTES (too long to build: they stay interpreted)."""
    if not available():
        raise CompilerMissing(f"C compiler '{COMPILER}' not found")
    folder = cache_dir()
    with tempfile.TemporaryDirectory(dir=folder) as tmp:
        source = Path(tmp) / "nlp.c"
        cwd = os.getcwd()
        os.chdir(tmp)  # generate_dependencies writes into the working directory
        try:
            solver.generate_dependencies(source.name)
        finally:
            os.chdir(cwd)
        text = source.read_bytes()
        if len(text) > MAX_SOURCE_BYTES:
            return None
        key = hashlib.sha256(text + " ".join((COMPILER, *FLAGS, ca.__version__)).encode())
        target = folder / f"{key.hexdigest()[:20]}.so"
        if not target.exists():
            built = Path(tmp) / "nlp.so"
            subprocess.run([COMPILER, *FLAGS, str(source), "-o", str(built), "-lm"],
                           check=True, capture_output=True)
            os.replace(built, target)
    return target


def function(f: ca.Function) -> ca.Function:
    """f compiled to C (cached like the NLPs' libraries) and loaded back; f itself where no
    C compiler is found or its source is over MAX_SOURCE_BYTES."""
    if not available():
        return f
    folder = cache_dir()
    with tempfile.TemporaryDirectory(dir=folder) as tmp:
        source = Path(tmp) / f"{f.name()}.c"
        cwd = os.getcwd()
        os.chdir(tmp)
        try:
            f.generate(source.name)
        finally:
            os.chdir(cwd)
        text = source.read_bytes()
        if len(text) > MAX_SOURCE_BYTES:
            return f
        key = hashlib.sha256(text + " ".join((COMPILER, *FLAGS, ca.__version__)).encode())
        target = folder / f"{key.hexdigest()[:20]}.so"
        if not target.exists():
            built = Path(tmp) / "function.so"
            subprocess.run([COMPILER, *FLAGS, str(source), "-o", str(built), "-lm"],
                           check=True, capture_output=True)
            os.replace(built, target)
    return ca.external(f.name(), str(target))


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
