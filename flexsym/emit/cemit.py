"""Emit C99 from a casadi SX function's instruction list, and count its operations.

casadi has already done common-subexpression elimination and register allocation (its
work slots); this printer writes one statement per instruction into local registers,
with typed, named, dense row-major arguments and no run-time null checks, so the code
compiles cleanly with -Wall -Wextra -Werror -pedantic and needs no work arrays.
"""
from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass

import casadi as ca

from flexsym.emit.kernels import Kernel

_OPS = {getattr(ca, n): n[3:] for n in dir(ca) if n.startswith("OP_")}

_BINARY = {"ADD": "{0} + {1}", "SUB": "{0} - {1}", "MUL": "{0} * {1}", "DIV": "{0} / {1}",
           "POW": "pow({0}, {1})", "CONSTPOW": "pow({0}, {1})", "ATAN2": "atan2({0}, {1})",
           "LT": "{0} < {1}", "LE": "{0} <= {1}", "EQ": "{0} == {1}", "NE": "{0} != {1}",
           "AND": "{0} && {1}", "OR": "{0} || {1}", "FMIN": "fmin({0}, {1})",
           "FMAX": "fmax({0}, {1})", "IF_ELSE_ZERO": "{0} ? {1} : 0.0",
           "FMOD": "fmod({0}, {1})"}
_UNARY = {"NEG": "-{0}", "SQ": "{0} * {0}", "TWICE": "2.0 * {0}", "INV": "1.0 / {0}",
          "SQRT": "sqrt({0})", "SIN": "sin({0})", "COS": "cos({0})", "TAN": "tan({0})",
          "EXP": "exp({0})", "LOG": "log({0})", "SINH": "sinh({0})", "COSH": "cosh({0})",
          "TANH": "tanh({0})", "ASIN": "asin({0})", "ACOS": "acos({0})", "ATAN": "atan({0})",
          "FABS": "fabs({0})", "NOT": "!{0}", "FLOOR": "floor({0})", "CEIL": "ceil({0})",
          "SIGN": "({0} > 0.0) - ({0} < 0.0)", "ASSIGN": "{0}"}

# Categories for operation counts (what a reader wants to compare between variants).
_CATEGORY = {"ADD": "add", "SUB": "add", "NEG": "add", "MUL": "mul", "SQ": "mul", "TWICE": "mul",
             "DIV": "div", "INV": "div"}


ZERO_LOOP = 16  # more zero entries in an output than this: one loop writes them


@dataclass
class EmittedKernel:
    kernel: Kernel
    c_name: str
    signature: str
    body: str
    ops: dict[str, int]
    used_inputs: frozenset = frozenset()  # names of the inputs the C reads

    @property
    def total_ops(self) -> int:
        return sum(self.ops.values())


def c_double(x: float) -> str:
    r = repr(float(x))
    if "inf" in r or "nan" in r:
        raise ValueError(f"non-finite constant {r} cannot be emitted")
    if "e" not in r and "." not in r:
        r += ".0"
    return f"({r})" if r.startswith("-") else r


def emit(kernel: Kernel, prefix: str) -> EmittedKernel:
    fn = kernel.function
    c_name = f"{prefix}{kernel.name}"
    args = [f"const double* {p.name}" for p in kernel.inputs] + [f"double* {p.name}" for p in kernel.outputs]
    signature = f"void {c_name}({', '.join(args)})"

    # casadi stores outputs column-major and sparse; we write dense row-major.
    out_index = []
    for k, port in enumerate(kernel.outputs):
        sp_ = fn.sparsity_out(k)
        rows, cols = sp_.get_triplet()
        out_index.append([r * port.cols + c for r, c in zip(rows, cols)])

    lines, used_inputs = [], set()  # lines: (C statement, register it assigns or None)
    zero_regs: dict[int, int] = {}  # register holding the constant 0 -> line of that assignment
    read: set[int] = set()  # lines of zero assignments that something reads
    written = [set() for _ in kernel.outputs]  # output entries stored from a nonzero register
    ops: Counter = Counter()
    reg = lambda i: f"a{i}"

    def assign(r, rhs, *reads):
        for x in reads:
            if x in zero_regs:
                read.add(zero_regs[x])
        zero_regs.pop(r, None)
        lines.append((f"{reg(r)} = {rhs};", r))

    for k in range(fn.n_instructions()):
        op = _OPS[fn.instruction_id(k)]
        ins, outs = fn.instruction_input(k), fn.instruction_output(k)
        if op == "INPUT":
            port = kernel.inputs[ins[0]]
            used_inputs.add(port.name)
            assign(outs[0], f"{port.name}[{_dense_in(fn, ins[0], ins[1], port)}]")
        elif op == "OUTPUT":
            if ins[0] in zero_regs:  # a zero entry: written with the zeros below
                continue
            port = kernel.outputs[outs[0]]
            written[outs[0]].add(out_index[outs[0]][outs[1]])
            lines.append((f"{port.name}[{out_index[outs[0]][outs[1]]}] = {reg(ins[0])};", None))
        elif op == "CONST":
            value = fn.instruction_constant(k)
            assign(outs[0], c_double(value))
            if value == 0.0 and math.copysign(1.0, value) > 0:  # +0.0 (-0.0 keeps its sign)
                zero_regs[outs[0]] = len(lines) - 1
        elif op in _BINARY:
            assign(outs[0], _BINARY[op].format(reg(ins[0]), reg(ins[1])), ins[0], ins[1])
            ops[_CATEGORY.get(op, "other")] += 1
        elif op in _UNARY:
            assign(outs[0], _UNARY[op].format(reg(ins[0])), ins[0])
            if op != "ASSIGN":
                ops[_CATEGORY.get(op, "fun")] += 1
        else:
            raise ValueError(f"kernel {kernel.name}: casadi operation {op} has no C printer")
    # a zero constant only stored to outputs is not needed (and would be an unused variable)
    unread = {i for i, (text, r) in enumerate(lines)
              if r is not None and text == f"{reg(r)} = 0.0;" and i not in read}
    lines = [x for i, x in enumerate(lines) if i not in unread]
    registers = {r for _, r in lines if r is not None}

    body = []
    for port in kernel.inputs:
        if port.name not in used_inputs:
            body.append(f"(void){port.name};  /* not needed by this variant */")
    # Zero entries first, by a loop when there are many: thousands of separate zero stores
    # (dense Jacobians of ef systems) cost gcc most of its time (alias analysis of stores).
    for k, port in enumerate(kernel.outputs):
        zeros = [i for i in range(port.size) if i not in written[k]]
        if len(zeros) > ZERO_LOOP:
            body.append(f"for (int i = 0; i < {port.size}; ++i) {port.name}[i] = 0.0;")
        else:
            body.extend(f"{port.name}[{i}] = 0.0;" for i in zeros)
    if registers:
        body.append("double " + ", ".join(reg(i) for i in sorted(registers)) + ";")
    body.extend(text for text, _ in lines)
    return EmittedKernel(kernel, c_name, signature, "\n".join("  " + b for b in body),
                         {c: ops.get(c, 0) for c in ("add", "mul", "div", "fun", "other")},
                         frozenset(used_inputs))


def _dense_in(fn: ca.Function, i: int, nz: int, port) -> int:
    rows, cols = fn.sparsity_in(i).get_triplet()
    return rows[nz] * port.cols + cols[nz]
