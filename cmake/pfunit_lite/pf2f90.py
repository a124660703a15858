#!/usr/bin/env python3
"""pf2f90: turn the subset of pFUnit 4 ``.pf`` syntax used by vci into plain Fortran.

Used only when pFUnit is not installed (see docs/TESTING.md for the exact subset).

  pf2f90.py SUITE.pf -o SUITE.F90        convert one test module
  pf2f90.py A.pf B.pf --driver MAIN.F90  write a program that runs every @test

Both can be combined.  Errors are reported as ``file:line: error: ...`` and
exit with status 1 before any output file is written.
"""

import argparse
import os
import re
import sys

# Assertions provided by cmake/pfunit_lite/funit.f90 (keep in sync with it and docs).
ASSERTIONS = [
    "assertEqual", "assertTrue", "assertFalse",
    "assertLessThan", "assertLessThanOrEqual",
    "assertGreaterThan", "assertGreaterThanOrEqual",
    "assertRelativelyEqual", "assertIsFinite",
]
_ASSERT_BY_LOWER = {a.lower(): a for a in ASSERTIONS}
_PROC_DIRECTIVES = ("test", "before", "after")

_DIRECTIVE_RE = re.compile(r"^(\s*)@(\w+)(.*)$")
_MODULE_RE = re.compile(r"^\s*module\s+(\w+)\s*(!.*)?$", re.I)
_END_MODULE_RE = re.compile(r"^\s*end\s*module\b", re.I)
_CONTAINS_RE = re.compile(r"^\s*contains\s*(!.*)?$", re.I)
_SUBROUTINE_RE = re.compile(
    r"^\s*(?:(?:recursive|impure|module)\s+)*subroutine\s+(\w+)\s*(\([^)]*\))?\s*(!.*)?$", re.I)


class PfError(Exception):
    def __init__(self, path, line, msg):
        super().__init__("%s:%d: error: %s" % (path, line, msg))


def split_comment(line):
    """Return (code, comment) of one free-form line, ignoring '!' inside strings."""
    quote = None
    for i, ch in enumerate(line):
        if quote:
            if ch == quote:
                quote = None  # a doubled quote ('') just re-opens on the next char
        elif ch in "'\"":
            quote = ch
        elif ch == "!":
            return line[:i], line[i:]
    return line, ""


def is_blank_or_comment(line):
    return split_comment(line)[0].strip() == ""


def find_closing_paren(lines, first, col):
    """Locate the ')' matching the '(' at lines[first][col].

    Scans across '&' continuation lines, skipping strings and comments.
    Returns (line_index, column).
    """
    depth, quote = 0, None
    i, j = first, col
    while i < len(lines):
        text = lines[i]
        while j < len(text):
            ch = text[j]
            if quote:
                if ch == quote:
                    quote = None
            elif ch in "'\"":
                quote = ch
            elif ch == "!":
                break  # rest of the line is a comment
            elif ch == "(":
                depth += 1
            elif ch == ")":
                depth -= 1
                if depth == 0:
                    return i, j
            j += 1
        i, j = i + 1, 0
    return None


class Suite:
    """What the driver needs to know about one converted .pf file."""

    def __init__(self, path):
        self.path = path
        self.module = None
        self.tests = []    # subroutine names, in file order
        self.before = None
        self.after = None
        self.output = []   # generated lines (without newlines)


def fortran_str(text):
    return "'" + text.replace("'", "''") + "'"


def parse(path):
    with open(path, encoding="utf-8") as f:
        lines = f.read().splitlines()
    suite = Suite(path)
    base = os.path.basename(path)
    cpp_path = os.path.abspath(path).replace("\\", "/").replace('"', '\\"')
    out = suite.output
    # '#line' makes compiler diagnostics point into the .pf file.
    out.append('#line 1 "%s"' % cpp_path)
    in_contains = False
    ended = False
    pending = None  # (directive, line number) waiting for its subroutine

    i = 0
    while i < len(lines):
        line, lineno = lines[i], i + 1
        m = _DIRECTIVE_RE.match(line)
        if not m:
            if suite.module is None:
                mm = _MODULE_RE.match(line)
                if mm:
                    suite.module = mm.group(1)
            elif _CONTAINS_RE.match(line):
                in_contains = True
            elif _END_MODULE_RE.match(line):
                ended = True
            if pending and not is_blank_or_comment(line):
                sm = _SUBROUTINE_RE.match(line)
                kind, where = pending
                if not sm:
                    raise PfError(path, where, "@%s must be followed by a 'subroutine name()' "
                                  "statement" % kind)
                if sm.group(2) and sm.group(2)[1:-1].strip():
                    raise PfError(path, lineno, "test procedures must not take arguments "
                                  "(pFUnit TestCase classes are not supported)")
                name = sm.group(1)
                if kind == "test":
                    if name.lower() in (t.lower() for t in suite.tests):
                        raise PfError(path, lineno, "duplicate @test '%s'" % name)
                    suite.tests.append(name)
                else:
                    setattr(suite, kind, name)
                pending = None
            out.append(line)
            i += 1
            continue

        indent, word, rest = m.group(1), m.group(2), m.group(3)
        key = word.lower()
        if suite.module is None or not in_contains or ended:
            raise PfError(path, lineno, "@%s is only allowed between 'contains' and "
                          "'end module' of the test module" % word)
        if pending:
            raise PfError(path, pending[1], "@%s must be followed by a subroutine" % pending[0])

        if key in _PROC_DIRECTIVES:
            if rest.strip().startswith("("):
                raise PfError(path, lineno, "@%s(...) options are not supported" % word)
            if split_comment(rest)[0].strip():
                raise PfError(path, lineno, "unexpected text after @%s" % word)
            if key != "test" and getattr(suite, key):
                raise PfError(path, lineno, "only one @%s per module is supported" % word)
            pending = (key, lineno)
            out.append(indent + "! @" + word)  # keep the line count unchanged
            i += 1
            continue

        if key not in _ASSERT_BY_LOWER:
            raise PfError(path, lineno, "unsupported directive @%s (supported: @test, @before, "
                          "@after, @%s)" % (word, ", @".join(ASSERTIONS)))
        if not rest.lstrip().startswith("("):
            raise PfError(path, lineno, "expected '(' after @%s" % word)

        # Expand: call assertX(<args>, location='file:line'); if (anyExceptions()) return
        end = find_closing_paren(lines, i, len(indent) + 1 + len(word) + rest.index("("))
        if end is None:
            raise PfError(path, lineno, "unbalanced parentheses in @%s" % word)
        last, col = end
        macro = [indent + "call " + word + rest] + lines[i + 1:last + 1]
        k = last - i
        if k == 0:
            col += len("call ") - len("@")  # the first line was rewritten
        if split_comment(macro[k][col + 1:])[0].strip():
            raise PfError(path, last + 1, "unexpected text after @%s(...)" % word)
        location = fortran_str("%s:%d" % (base, lineno))
        macro[k] = macro[k][:col] + ", location=" + location + macro[k][col:]
        out.extend(macro)
        out.append(indent + "if (anyExceptions()) return")
        out.append('#line %d "%s"' % (last + 2, cpp_path))
        i = last + 1

    if suite.module is None:
        raise PfError(path, 1, "no 'module <name>' statement found")
    if not ended:
        raise PfError(path, len(lines), "missing 'end module'")
    if pending:
        raise PfError(path, pending[1], "@%s at end of module" % pending[0])
    stem = os.path.splitext(base)[0]
    if suite.module.lower() != stem.lower():
        # pFUnit's generated registry assumes this; enforce it so suites stay portable.
        raise PfError(path, 1, "module name '%s' must match the file name '%s'"
                      % (suite.module, stem))
    if not suite.tests:
        raise PfError(path, 1, "no @test procedures found")
    return suite


def driver_lines(suites):
    """A main program that runs every test through funit_run and exits nonzero on failure."""
    uses, calls = [], []
    for s_idx, s in enumerate(suites, 1):
        hooks = []
        for kind in ("before", "after"):
            proc = getattr(s, kind)
            if proc:
                alias = "s%d_%s" % (s_idx, kind)
                uses.append("  use %s, only: %s => %s" % (s.module, alias, proc))
                hooks.append("%s=%s" % (kind, alias))
        for t_idx, test in enumerate(s.tests, 1):
            alias = "s%d_t%d" % (s_idx, t_idx)
            uses.append("  use %s, only: %s => %s" % (s.module, alias, test))
            # One argument per line keeps every line short for any compiler.
            args = [fortran_str("%s.%s" % (s.module, test)), alias] + hooks
            calls.append("  call funit_run( &")
            calls.extend("    %s%s" % (a, ", &" if n < len(args) - 1 else ")")
                         for n, a in enumerate(args))
    return (["! Generated by pf2f90.py -- do not edit.", "program funit_lite_driver",
             "  use funit, only: funit_run, funit_summary"] + uses
            + ["  implicit none"] + calls + ["  call funit_summary()", "end program funit_lite_driver"])


def write(path, lines):
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w", encoding="utf-8") as f:
        f.write("\n".join(lines) + "\n")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("inputs", nargs="+", metavar="FILE.pf")
    ap.add_argument("-o", "--output", help="converted module (.F90); needs exactly one input")
    ap.add_argument("--driver", help="driver program (.F90) running all tests of the inputs")
    args = ap.parse_args(argv)
    if not args.output and not args.driver:
        ap.error("nothing to do: give -o and/or --driver")
    if args.output and len(args.inputs) != 1:
        ap.error("-o converts exactly one input file")
    try:
        suites = [parse(p) for p in args.inputs]
    except PfError as e:
        print(e, file=sys.stderr)
        return 1
    except OSError as e:
        print("pf2f90: error: %s" % e, file=sys.stderr)
        return 1
    modules = [s.module.lower() for s in suites]
    if len(set(modules)) != len(modules):
        print("pf2f90: error: the same test module appears twice", file=sys.stderr)
        return 1
    if args.output:
        write(args.output, ["! Generated from %s by pf2f90.py -- do not edit."
                            % os.path.basename(args.inputs[0])] + suites[0].output)
    if args.driver:
        write(args.driver, driver_lines(suites))
    return 0


if __name__ == "__main__":
    sys.exit(main())
