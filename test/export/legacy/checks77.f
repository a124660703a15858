C     Checks shared by the legacy test programs (pendw77.f, sepw77.f,
C     chainb77.f, chainp77.f):
C     each prints what failed and counts it in NBAD, so that a program
C     reports every failed check before it stops with status 1.
C     (ellipse77.f keeps its own: it is also built alone, as a user's
C     single-file program, by run_export_test.sh and doc_link_lines.sh.)
C
C     CHECKI: an integer equal to the expected one.
      SUBROUTINE CHECKI(WHAT, IVAL, IEXP, NBAD)
      CHARACTER*(*) WHAT
      INTEGER IVAL, IEXP, NBAD
      IF (IVAL .NE. IEXP) THEN
        WRITE (*, '(3A, I6, A, I6)') ' FAIL ', WHAT, ':', IVAL,
     &    ' expected', IEXP
        NBAD = NBAD + 1
      END IF
      END
C
C     CHECKR: a real within TOL of the expected one (NaN fails).
      SUBROUTINE CHECKR(WHAT, VAL, EXP, TOL, NBAD)
      CHARACTER*(*) WHAT
      DOUBLE PRECISION VAL, EXP, TOL
      INTEGER NBAD
      IF (.NOT. (ABS(VAL - EXP) .LE. TOL)) THEN
        WRITE (*, '(3A, 2ES25.17)') ' FAIL ', WHAT, ':', VAL, EXP
        NBAD = NBAD + 1
      END IF
      END
C
C     CHECKS: a message that contains PART.
      SUBROUTINE CHECKS(WHAT, MSG, PART, NBAD)
      CHARACTER*(*) WHAT, MSG, PART
      INTEGER NBAD
      IF (INDEX(MSG, PART) .EQ. 0) THEN
        WRITE (*, '(5A)') ' FAIL ', WHAT, ': no "', PART, '"'
        NBAD = NBAD + 1
      END IF
      END
