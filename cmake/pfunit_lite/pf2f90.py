#!/usr/bin/env python3
"""pf2f90: turn the subset of pFUnit 4 ``.pf`` syntax used by vci into plain Fortran.

Used only when pFUnit is not installed (see docs/TESTING.md for the exact subset).

  pf2f90.py SUITE.pf -o SUITE.F90        convert one test module
  pf2f90.py A.pf B.pf --driver MAIN.F90  write a program that runs every @test

Both can be combined.  Errors are reported as ``file:line: error: [rule] ...`` and
exit with status 1 before any output file is written.

The converter accepts only what pFUnit 4's own preprocessor (funitproc) expands into
code that compiles: a construct pFUnit would copy through unexpanded, or expand into a
line gfortran truncates, is rejected here with the name of the rule it breaks.
"""

import argparse
import os
import re
import sys

# Assertions provided by cmake/pfunit_lite/funit.f90 (keep in sync with it and docs).
# All of them exist in pFUnit 4, with the same argument order and the keywords tolerance=
# and message=.
ASSERTIONS = [
    "assertEqual", "assertTrue", "assertFalse",
    "assertLessThan", "assertLessThanOrEqual",
    "assertGreaterThan", "assertGreaterThanOrEqual",
    "assertRelativelyEqual", "assertIsFinite",
]
_ASSERT_BY_LOWER = {a.lower(): a for a in ASSERTIONS}
# pFUnit's procedures for these have no tolerance argument at all.
_NO_TOLERANCE = {"asserttrue", "assertfalse", "assertisfinite"}
# Keyword arguments a .pf file may use: pFUnit's dummy names for the operands differ
# between its specific procedures (expected/found, lhs/rhs, condition, x), and
# location= is added by the expansion itself.
_KEYWORDS = ("tolerance", "message")
_PROC_DIRECTIVES = ("test", "before", "after")

# gfortran's free-form limit (the default -ffree-line-length-132; a longer line is an
# error, -Werror=line-truncation, unless only blanks or a comment pass column 132).
LINE_LIMIT = 132
# pFUnit 4 writes '@assertX(ARGS)' as '  call assertX(ARGS, &' followed by the location
# on continuation lines (funit/pFUnitParser.py, AtAssert.action).
_PF_CALL = "  call assert%s(%s, &"

# pFUnit's regular expressions (pFUnitParser.py), applied to the whole line.
_PF_ASSERT_RE = re.compile(r"^\s*@assert(\w+)\s*\((.*)\)\s*$", re.I)
_PF_SUBROUTINE_RE = re.compile(r"^\s*subroutine\s+(\w*)\s*(\([\w\s,]*\))?\s*(!.*)*$", re.I)
_PF_MODULE_RE = re.compile(r"^\s*module\s+(\w*)\s*$", re.I)

_DIRECTIVE_RE = re.compile(r"^(\s*)@(\w+)(.*)$")
_MODULE_RE = re.compile(r"^\s*module\s+(?!procedure\b)(\w+)", re.I)
_END_MODULE_RE = re.compile(r"^\s*end\s*module\b", re.I)
_CONTAINS_RE = re.compile(r"^\s*contains\s*(!.*)?$", re.I)
_ANY_SUBROUTINE_RE = re.compile(r"^\s*(?:\w+\s+)*subroutine\s+\w+", re.I)
_KEYWORD_RE = re.compile(r"^\s*([A-Za-z]\w*)\s*=(?![=>])")


class PfError(Exception):
    def __init__(self, path, line, rule, msg):
        super().__init__("%s:%d: error: [%s] %s" % (path, line, rule, msg))


class PfErrors(Exception):
    """Several line-local errors of one file, reported together."""

    def __init__(self, errors):
        super().__init__("\n".join(str(e) for e in errors))


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


def split_args(text):
    """Split a macro's argument text at top-level commas, or return None if the
    parentheses close before the end of the text (i.e. the text is not one list)."""
    args, depth, quote, start = [], 0, None, 0
    for i, ch in enumerate(text):
        if quote:
            if ch == quote:
                quote = None
        elif ch in "'\"":
            quote = ch
        elif ch in "([":
            depth += 1
        elif ch in ")]":
            depth -= 1
            if depth < 0:
                return None
        elif ch == "," and depth == 0:
            args.append(text[start:i])
            start = i + 1
    if depth != 0 or quote:
        return None
    args.append(text[start:])
    return args


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


def expand_assert(path, base, lineno, line, word):
    """Check one @assert line against pFUnit's rules; return pFUnit's (ARGS) text."""
    code, comment = split_comment(line)
    if code.rstrip().endswith("&"):
        raise PfError(path, lineno, "continuation",
                      "@%s continues onto the next line with '&': pFUnit 4 expands only a "
                      "macro written on one line (put long operands in variables first)" % word)
    if comment:
        raise PfError(path, lineno, "trailing-comment",
                      "'!' comment after @%s(...): pFUnit 4 does not expand a macro line "
                      "that carries a comment (put the comment on the line above)" % word)
    m = _PF_ASSERT_RE.match(code)
    args = split_args(m.group(2)) if m else None
    if args is None:
        raise PfError(path, lineno, "one-call",
                      "@%s must be a single parenthesised argument list and nothing "
                      "after it" % word)
    key = word.lower()
    for a in args:
        km = _KEYWORD_RE.match(a)
        if not km:
            continue
        kw = km.group(1).lower()
        if kw not in _KEYWORDS:
            raise PfError(path, lineno, "keyword",
                          "keyword argument '%s=' in @%s: only tolerance= and message= are "
                          "allowed (pFUnit's operand names differ between its procedures; "
                          "location= is added by the macro)" % (km.group(1), word))
        if kw == "tolerance" and key in _NO_TOLERANCE:
            raise PfError(path, lineno, "keyword",
                          "pFUnit's %s has no tolerance argument" % word)
    expanded = _PF_CALL % (m.group(1), m.group(2))
    if len(expanded) > LINE_LIMIT:
        raise PfError(path, lineno, "line-length",
                      "@%s expands under pFUnit 4 to a line of %d characters ('%s'), over "
                      "gfortran's limit of %d: shorten the arguments by %d characters"
                      % (word, len(expanded), _PF_CALL % (m.group(1), "..."), LINE_LIMIT,
                         len(expanded) - LINE_LIMIT))
    return m.group(1), m.group(2)


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
    errors = []     # line-local rule violations, reported together at the end

    for i, line in enumerate(lines):
        lineno = i + 1
        m = _DIRECTIVE_RE.match(line)
        if not m:
            code = split_comment(line)[0].rstrip()
            if len(code) > LINE_LIMIT:
                errors.append(PfError(path, lineno, "line-length",
                                      "code extends to column %d; gfortran (as pFUnit 4 "
                                      "compiles it) stops at column %d" % (len(code), LINE_LIMIT)))
            if suite.module is None:
                mm = _MODULE_RE.match(line)
                if mm:
                    if not _PF_MODULE_RE.match(line):
                        raise PfError(path, lineno, "module",
                                      "write the module statement as 'module <name>' alone "
                                      "on its line: pFUnit 4 does not recognise it otherwise")
                    suite.module = mm.group(1)
            elif _CONTAINS_RE.match(line):
                in_contains = True
            elif _END_MODULE_RE.match(line):
                ended = True
            if pending and not is_blank_or_comment(line):
                kind, where = pending
                sm = _PF_SUBROUTINE_RE.match(line)
                if not sm or not sm.group(1):
                    if _ANY_SUBROUTINE_RE.match(line):
                        raise PfError(path, lineno, "procedure",
                                      "the procedure after @%s must start 'subroutine name()': "
                                      "pFUnit 4 does not recognise prefixes such as "
                                      "recursive/impure/module" % kind)
                    raise PfError(path, where, "procedure",
                                  "@%s must be followed by a 'subroutine name()' statement"
                                  % kind)
                if sm.group(2) and sm.group(2)[1:-1].strip():
                    raise PfError(path, lineno, "procedure",
                                  "test procedures must not take arguments "
                                  "(pFUnit TestCase classes are not supported)")
                name = sm.group(1)
                if kind == "test":
                    if name.lower() in (t.lower() for t in suite.tests):
                        raise PfError(path, lineno, "procedure", "duplicate @test '%s'" % name)
                    suite.tests.append(name)
                else:
                    setattr(suite, kind, name)
                pending = None
            out.append(line)
            continue

        indent, word, rest = m.group(1), m.group(2), m.group(3)
        key = word.lower()
        if suite.module is None or not in_contains or ended:
            raise PfError(path, lineno, "placement",
                          "@%s is only allowed between 'contains' and 'end module' of the "
                          "test module" % word)
        if pending:
            raise PfError(path, pending[1], "procedure",
                          "@%s must be followed by a subroutine" % pending[0])

        if key in _PROC_DIRECTIVES:
            if rest.strip().startswith("("):
                raise PfError(path, lineno, "directive", "@%s(...) options are not supported"
                              % word)
            if rest.strip():
                raise PfError(path, lineno, "directive",
                              "nothing may follow @%s on its line, not even a comment: "
                              "pFUnit 4 does not recognise it otherwise" % word)
            if key != "test" and getattr(suite, key):
                raise PfError(path, lineno, "directive", "only one @%s per module is "
                              "supported" % word)
            pending = (key, lineno)
            out.append(indent + "! @" + word)  # keep the line count unchanged
            continue

        if key not in _ASSERT_BY_LOWER:
            errors.append(PfError(path, lineno, "assertion",
                                  "unsupported directive @%s (supported: @test, @before, "
                                  "@after, @%s)" % (word, ", @".join(ASSERTIONS))))
            continue
        try:
            name, args = expand_assert(path, base, lineno, line, word)
        except PfError as e:
            errors.append(e)
            continue
        # The same layout as pFUnit 4's expansion, so that gfortran's line limit applies
        # to the same lines; the location is a plain string here.  Both lines of the call
        # are marked as line `lineno`: gfortran reports some errors (no specific procedure
        # for a generic) at the end of the statement.
        out.append('#line %d "%s"' % (lineno, cpp_path))
        out.append(_PF_CALL % (name, args))
        out.append('#line %d "%s"' % (lineno, cpp_path))
        out.append(" & location=%s)" % fortran_str("%s:%d" % (base, lineno)))
        out.append("  if (anyExceptions()) return")
        out.append('#line %d "%s"' % (lineno + 1, cpp_path))

    if errors:
        raise PfErrors(errors)
    if suite.module is None:
        raise PfError(path, 1, "module", "no 'module <name>' statement found")
    if not ended:
        raise PfError(path, len(lines), "module", "missing 'end module'")
    if pending:
        raise PfError(path, pending[1], "procedure", "@%s at end of module" % pending[0])
    stem = os.path.splitext(base)[0]
    if suite.module.lower() != stem.lower():
        # pFUnit's generated registry assumes this; enforce it so suites stay portable.
        raise PfError(path, 1, "module", "module name '%s' must match the file name '%s'"
                      % (suite.module, stem))
    if not suite.tests:
        raise PfError(path, 1, "procedure", "no @test procedures found")
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
    except (PfError, PfErrors) as e:
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
