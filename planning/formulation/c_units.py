"""CasADi's generated C of one function split into several translation units, so that gcc
builds them in parallel (planning.formulation.compiled's quick builds).

An SX function's C is straight-line code in one C function per CasADi function (the site
derivatives called, the body using them); the Panda's anytime-SQP model is one 190,000-line
function, which gcc -O0 builds in one ~14 s job. A body over `part_bytes` is cut into
consecutive parts, each a C function of its own unit: the locals a part reads before it writes
them are loaded from an array the caller passes, those a later part reads are stored there.
The statements and their order are unchanged, so the results are the same bits
(tests/test_planning_compiled.py). Code that does not have the expected shape is left whole.
"""

from __future__ import annotations

import math
import re

# a function definition at the start of a line: (static )(return type) name(parameters) {
_DEFINITION = re.compile(r"^(static )?([A-Za-z_][\w ]*?[\w*]) ?\b(\w+)\(([^)]*)\)\s*\{")
_LOCAL = re.compile(r"\ba\d+\b")
_ASSIGNED = re.compile(r"^\s*(a\d+)\s*=(?!=)")
_SIGNATURE = ("const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, "
              "int mem")
_HIDDEN = '__attribute__((visibility("hidden"))) '
_DECLARATION = "  casadi_real a"


def split(text: str, part_bytes: int) -> list[str]:
    """The C of `text` (one CasADi-generated file) as units: the first the file with each
    function body over part_bytes replaced by calls of its parts, then one unit per part;
    [text] if no body is split."""
    lines = text.split("\n")
    functions = _functions(lines)
    if not functions:
        return [text]
    replaced, parts = {}, []
    for begin, end, match in functions:
        cut = _parts(lines, begin, end, match, part_bytes)
        if cut is not None:
            replaced[begin] = (end, cut[0])
            parts += cut[1]
    if not parts:
        return [text]
    first = functions[0][0]
    prototypes = [f"{_HIDDEN}{m.group(2)} {m.group(3)}({m.group(4)});"
                  for _, _, m in functions if "CASADI_SYMBOL_EXPORT" not in m.group(0)]
    head = lines[:first] + _constants(lines) + prototypes
    main, i = lines[:first] + [f"{_HIDDEN}int {name}({_SIGNATURE}, casadi_real* live);"
                               for name, _ in parts], first
    while i < len(lines):
        if i in replaced:
            end, body = replaced[i]
            main += [_unstatic(lines[i]), *body, "}"]
            i = end + 1
        else:
            main.append(_unstatic(lines[i]) if _DEFINITION.match(lines[i]) else lines[i])
            i += 1
    closing = ["#ifdef __cplusplus", '} /* extern "C" */', "#endif", ""]
    return ["\n".join(main)] + ["\n".join([*head, f"{_HIDDEN}int {name}({_SIGNATURE}, "
                                           "casadi_real* live) {", *body, "}", *closing])
                                for name, body in parts]


def _functions(lines: list[str]) -> list[tuple[int, int, re.Match]]:
    """(first line, last line, definition match) of each function defined in the file."""
    found = []
    for i, line in enumerate(lines):
        match = _DEFINITION.match(line)
        if match is None:
            continue
        if line.rstrip().endswith("}") and line.count("{") == line.count("}"):
            found.append((i, i, match))
            continue
        end = next((j for j in range(i + 1, len(lines)) if lines[j] == "}"), None)
        if end is None:
            return []
        found.append((i, end, match))
    return found


def _constants(lines: list[str]) -> list[str]:
    """The file's static constant arrays (each from its "static const" line to its ";")."""
    found, inside = [], False
    for line in lines:
        inside = inside or line.startswith("static const ")
        if inside:
            found.append(line)
            inside = not line.rstrip().endswith(";")
    return found


def _parts(lines, begin, end, match, part_bytes):
    """(the function's new body, [(part name, part body)]) if it is a static evaluation
    function of straight-line statements over part_bytes, else None."""
    size = sum(len(line) + 1 for line in lines[begin:end + 1])
    if not match.group(1) or match.group(4) != _SIGNATURE or size <= part_bytes:
        return None
    body = lines[begin + 1:end]
    k = 0
    while k < len(body) and body[k].startswith(_DECLARATION):
        k += 1
    statements = body[k:]
    if not statements or statements[-1] != "  return 0;":
        return None
    statements = statements[:-1]
    if any("{" in s or "}" in s or not s.endswith(";") for s in statements):
        return None
    count = math.ceil(size / part_bytes)
    bounds = [round(j * len(statements) / count) for j in range(count + 1)]
    chunks = [statements[bounds[j]:bounds[j + 1]] for j in range(count)]
    reads, writes = zip(*map(_live, chunks), strict=True)
    slots: dict[str, int] = {}
    parts = []
    for j, chunk in enumerate(chunks):
        later = set().union(*reads[j + 1:])
        stores = sorted(writes[j] & later)
        for name in [*reads[j], *stores]:
            slots.setdefault(name, len(slots))
        used = sorted(set(_LOCAL.findall("\n".join(chunk))))
        declared = [f"{_DECLARATION[:-1]}{', '.join(used[a:a + 12])};"
                    for a in range(0, len(used), 12)]
        parts.append((f"CASADI_PREFIX({match.group(3).removeprefix('casadi_')}_part{j})", [
            *declared, *(f"  {name} = live[{slots[name]}];" for name in reads[j]), *chunk,
            *(f"  live[{slots[name]}] = {name};" for name in stores), "  return 0;"]))
    calls = [f"  if ({name}(arg, res, iw, w, mem, live)) return 1;" for name, _ in parts]
    return [f"  casadi_real live[{max(len(slots), 1)}];", *calls, "  return 0;"], parts


def _live(chunk: list[str]) -> tuple[list[str], set[str]]:
    """The locals a chunk reads before writing them (in order) and those it writes."""
    written: set[str] = set()
    reads: dict[str, None] = {}
    for statement in chunk:
        assigned = _ASSIGNED.match(statement)
        for name in _LOCAL.findall(statement[assigned.end():] if assigned else statement):
            if name not in written:
                reads.setdefault(name)
        if assigned:
            written.add(assigned.group(1))
    return list(reads), written


def _unstatic(line: str) -> str:
    """A static function's definition made global but hidden (the parts call it)."""
    return line.replace("static ", _HIDDEN, 1) if line.startswith("static ") else line
