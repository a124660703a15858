#!/usr/bin/env python3
"""check_reject: one self-test of pfunit_lite's rejection rules (docs/TESTING.md).

  check_reject.py --converter pf2f90.py --fc FC --lite-mod DIR --workdir DIR FILE.pf
                  [--pfunit-python PY --pfunit-proc funitproc --pfunit-mod DIR]

FILE.pf breaks one rule, on one line, and says so in its header comments:

  ! expect-error: LINE RULE           pf2f90.py fails with 'FILE.pf:LINE: error: [RULE]' only
  ! expect-compile-error: LINE WORD   pf2f90.py accepts FILE.pf; the compiler reports an Error
                                      at FILE.pf:LINE whose text contains WORD
  ! fix: LINE TEXT                    optional, repeatable: the repaired LINE (default: LINE
                                      of the expect line becomes blank)
  ! pfunit-output-lacks: TEXT         optional, see below

The repaired file (the control) must convert and compile.  With --pfunit-*, the same
two checks run under the real pFUnit (funitproc, then a syntax-only compile against its
modules): FILE.pf must fail with an error in FILE.pf and the control must compile, so
the rule rejects exactly the broken line, and pFUnit rejects it too.  Where pFUnit
instead drops a test or the module silently, 'pfunit-output-lacks: TEXT' says what
the code funitproc writes lacks for FILE.pf and contains for the control.
Exit status 0 when everything holds.
"""

import argparse
import os
import re
import subprocess
import sys

_EXPECT_RE = re.compile(r"^!\s*expect-(error|compile-error):\s*(\d+)\s+(\S+)\s*$")
_FIX_RE = re.compile(r"^!\s*fix:\s*(\d+)(?: (.*))?$")
_LACKS_RE = re.compile(r"^!\s*pfunit-output-lacks:\s*(.*\S)\s*$")
_REPORT_RE = re.compile(r"^(.*?):(\d+): error: \[([\w-]+)\]")


def run(cmd):
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                       universal_newlines=True)
    return p.returncode, p.stdout


def compile_errors(out, base, generated=False):
    """(line, text) of every gfortran 'Error:' located in the file named base, or with
    generated=True also in the .F90 made from it (where pFUnit copies a line it did not
    expand, before its first '#line' marker)."""
    names = {base}
    if generated:
        names.add(os.path.splitext(base)[0] + ".F90")
    found, where = [], None
    for text in out.splitlines():
        m = re.match(r"^(.*?):(\d+):\d+:\s*$", text)
        if m:
            where = (os.path.basename(m.group(1)), int(m.group(2)))
        elif text.startswith("Error:") and where and where[0] in names:
            found.append((where[1], text))
    return found


class Checker:
    def __init__(self, a):
        self.a = a
        self.ok = True

    def fail(self, msg):
        print("FAIL: " + msg)
        self.ok = False

    def fc(self, f90, mod_dir, work, label):
        os.makedirs(work, exist_ok=True)
        rc, out = run([self.a.fc, "-fsyntax-only", "-ffree-line-length-132",
                       "-Werror=line-truncation", "-I" + mod_dir, "-J" + work, f90])
        print("$ %s -fsyntax-only %s (%s)\n%s(exit %d)" % (self.a.fc, os.path.basename(f90),
                                                          label, out, rc))
        return rc, out

    def lite(self, pf, work):
        """pf2f90.py, then the compiler if it converted: (conversion rc, output, compile rc, output)."""
        os.makedirs(work, exist_ok=True)
        f90 = os.path.join(work, os.path.splitext(os.path.basename(pf))[0] + ".F90")
        rc, out = run([self.a.python, self.a.converter, pf, "-o", f90])
        print("$ pf2f90.py %s\n%s(exit %d)" % (os.path.basename(pf), out, rc))
        if rc != 0:
            return rc, out, None, ""
        crc, cout = self.fc(f90, self.a.lite_mod, work, "pfunit_lite")
        return rc, out, crc, cout

    def pfunit(self, pf, work):
        """funitproc, then the compiler if it succeeded: (rc, output, F90 text, compile rc, output)."""
        os.makedirs(work, exist_ok=True)
        f90 = os.path.join(work, os.path.splitext(os.path.basename(pf))[0] + ".F90")
        rc, out = run([self.a.pfunit_python, self.a.pfunit_proc, pf, f90])
        print("$ funitproc %s (real pFUnit)\n%s(exit %d)" % (os.path.basename(pf), out, rc))
        if rc != 0:
            return rc, out, "", None, ""
        with open(f90, encoding="utf-8") as f:
            # code only: the header comments that name TEXT are copied into the output
            text = "\n".join(t for t in f.read().splitlines() if not t.lstrip().startswith("!"))
        crc, cout = self.fc(f90, self.a.pfunit_mod, work, "real pFUnit")
        return rc, out, text, crc, cout


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("pf")
    ap.add_argument("--converter", required=True)
    ap.add_argument("--fc", required=True)
    ap.add_argument("--lite-mod", required=True)
    ap.add_argument("--workdir", required=True)
    ap.add_argument("--python", default=sys.executable)
    ap.add_argument("--pfunit-python")
    ap.add_argument("--pfunit-proc")
    ap.add_argument("--pfunit-mod")
    a = ap.parse_args()
    c = Checker(a)

    base = os.path.basename(a.pf)
    with open(a.pf, encoding="utf-8") as f:
        lines = f.read().splitlines()
    expects = [m.groups() for m in map(_EXPECT_RE.match, lines) if m]
    fixes = {int(m.group(1)): m.group(2) or "" for m in map(_FIX_RE.match, lines) if m}
    lacks = [m.group(1) for m in map(_LACKS_RE.match, lines) if m]
    if len(expects) != 1:
        print("%s: needs exactly one '! expect-...' header line" % a.pf)
        return 1
    kind, line, what = expects[0]
    line = int(line)
    if not fixes:
        fixes = {line: ""}

    # The control: the same file (same name, same line numbers) with the broken line repaired.
    ctl_dir = os.path.join(a.workdir, "control")
    os.makedirs(ctl_dir, exist_ok=True)
    control = os.path.join(ctl_dir, base)
    with open(control, "w", encoding="utf-8") as f:
        f.write("\n".join(fixes.get(i, t) for i, t in enumerate(lines, 1)) + "\n")

    print("== pfunit_lite, %s as written" % base)
    rc, out, crc, cout = c.lite(a.pf, os.path.join(a.workdir, "lite"))
    if kind == "error":
        got = [(int(m.group(2)), m.group(3)) for m in map(_REPORT_RE.match, out.splitlines())
               if m and os.path.basename(m.group(1)) == base]
        if rc == 0 or got != [(line, what)]:
            c.fail("pf2f90.py should report only %s:%d [%s]; reported %s" % (base, line, what, got))
    else:
        if rc != 0:
            c.fail("pf2f90.py should accept %s (the compiler is to reject it)" % base)
        elif crc == 0 or not any(n == line and what.lower() in t.lower()
                                 for n, t in compile_errors(cout, base)):
            c.fail("no compiler error at %s:%d mentioning '%s'" % (base, line, what))

    print("== pfunit_lite, control (line %s repaired)" % ", ".join(map(str, sorted(fixes))))
    rc, out, crc, cout = c.lite(control, os.path.join(a.workdir, "lite-control"))
    if rc != 0 or crc != 0:
        c.fail("the repaired file must convert and compile under pfunit_lite")

    if a.pfunit_proc:
        print("== real pFUnit, %s as written" % base)
        rc, out, text, crc, cout = c.pfunit(a.pf, os.path.join(a.workdir, "pfunit"))
        if lacks:
            for t in lacks:
                if t.lower() in text.lower():
                    c.fail("real pFUnit's output contains '%s': it handles %s" % (t, base))
                else:
                    print("real pFUnit's output lacks '%s'" % t)
        elif rc == 0 and (crc == 0 or not compile_errors(cout, base, generated=True)):
            c.fail("real pFUnit accepts %s, which pfunit_lite rejects" % base)
        print("== real pFUnit, control")
        rc, out, text, crc, cout = c.pfunit(control, os.path.join(a.workdir, "pfunit-control"))
        if rc != 0 or crc != 0:
            c.fail("the repaired file must compile under real pFUnit")
        for t in lacks:
            if t.lower() not in text.lower():
                c.fail("real pFUnit's output for the control lacks '%s' too" % t)

    print("OK" if c.ok else "FAILED")
    return 0 if c.ok else 1


if __name__ == "__main__":
    sys.exit(main())
