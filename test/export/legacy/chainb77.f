C     A declared Hessian bandwidth through vci's legacy entry points
C     (VCIBND, IOPT bit 64, TASK 18), as a Fortran 77 program: the
C     FPU-beta chain of N = 20 unit masses between walls |X(I)| <= 0.6
C     (fixed ends, springs R**2/2 + R**4/4), midpoint, h = 0.01, 100
C     steps, the hamiltonian impact condition, from docs/RESULTS.md's
C     start. 1. dense Hessians (TASK 13, IOPT 15) against banded ones
C     only (TASK 18, IOPT 78, VCIBND(IH, 1, 0)): the same impacts and
C     the same end state to 1E-9 (each solve meets rtol 1E-12). 2. the
C     band declared 0 with the check (VCIBND(IH, 0, 1)): VCIINM fails
C     with ISTAT = 1 and VCIMSG names L_qq(2, 1). Stops with code 1 if
C     anything is off. CHECKI, CHECKR, CHECKS: checks77.f.
      PROGRAM CHAINB
      IMPLICIT NONE
      EXTERNAL CBMOD
      INTEGER N, M, NG, LTIMP
      PARAMETER (N = 20, M = 0, NG = 40, LTIMP = 400)
      DOUBLE PRECISION H, T, Q(N), P(N), QD(N), PD(N), TIMP(LTIMP)
      DOUBLE PRECISION Q0(N), P0(N), RPAR(1), PI, DQ, DP
      INTEGER IPAR(2), NIMP, NIMPD, ISTAT, IH, NBAD, I, K, IOPT, N13
      CHARACTER*300 MSG
      NBAD = 0
      IPAR(1) = 1
      IPAR(2) = 0
      H = 1.0D-2
      PI = ACOS(-1.0D0)
      DO 5 I = 1, N
        Q0(I) = 0.24D0 * SIN(2 * PI * I / 21.0D0)
        P0(I) = 1.2D0 * SIN(3 * PI * I / 21.0D0)
     &        + 0.8D0 * SIN(PI * I / 21.0D0)
    5 CONTINUE
C
C     1. dense (K = 1) and banded (K = 2)
      DO 20 K = 1, 2
        IOPT = 15
        IF (K .EQ. 2) IOPT = 78
        CALL VCINEW(CBMOD, N, M, NG, IOPT, H, RPAR, IPAR, IH, ISTAT)
        CALL CHECKI('VCINEW', ISTAT, 0, NBAD)
        IF (K .EQ. 2) THEN
          CALL VCIBND(IH, 1, 0, ISTAT)
          CALL CHECKI('VCIBND', ISTAT, 0, NBAD)
        END IF
        CALL VCIENG(IH, 1, ISTAT)
        CALL CHECKI('VCIENG hamiltonian', ISTAT, 0, NBAD)
        CALL VCIINM(IH, 0.0D0, Q0, P0, ISTAT)
        CALL CHECKI('VCIINM', ISTAT, 0, NBAD)
        CALL VCIADV(IH, 100, 1, T, Q, P, NIMP, TIMP, LTIMP, ISTAT)
        IF (ISTAT .NE. 0) THEN
          CALL VCIMSG(IH, MSG)
          WRITE (*, '(2A)') ' VCIADV: ', MSG(1:200)
        END IF
        CALL CHECKI('VCIADV', ISTAT, 0, NBAD)
        CALL VCIDEL(IH)
        IF (K .EQ. 1) THEN
          N13 = IPAR(2)
          IPAR(2) = 0
          NIMPD = NIMP
          DO 10 I = 1, N
            QD(I) = Q(I)
            PD(I) = P(I)
   10     CONTINUE
        END IF
   20 CONTINUE
      DQ = 0.0D0
      DP = 0.0D0
      DO 30 I = 1, N
        DQ = MAX(DQ, ABS(Q(I) - QD(I)))
        DP = MAX(DP, ABS(P(I) - PD(I)))
   30 CONTINUE
      WRITE (*, '(A, 2I4, A, 2ES10.2)') ' impacts dense, banded:',
     &  NIMPD, NIMP, '  |dq|, |dp|:', DQ, DP
      CALL CHECKI('banded impacts = dense', NIMP, NIMPD, NBAD)
C     the banded run takes its Jacobians from TASK 18 as the dense one
C     from TASK 13 (not differenced, which never calls it): at least 20
C     calls, and no more than the dense run's plus 20 % (a banded stage
C     keeps its block for the sub-steps after it, issue 28: 28 against
C     49 calls; the dense run's impact stages keep their block as a
C     chord: a few to 12 % more Newton iterations)
      WRITE (*, '(A, 2I6)') ' calls of TASK 13 (dense), 18 (banded):',
     &  N13, IPAR(2)
      IF (N13 .LT. 20 .OR. IPAR(2) .LT. 20 .OR.
     &  5 * (IPAR(2) - N13) .GT. N13)
     &  CALL CHECKI('TASK 18 used', 0, 1, NBAD)
      IF (NIMPD .LT. 10) CALL CHECKI('dense impacts >= 10', 0, 1, NBAD)
      CALL CHECKR('banded q - dense q', DQ, 0.0D0, 1.0D-9, NBAD)
      CALL CHECKR('banded p - dense p', DP, 0.0D0, 1.0D-9, NBAD)
C
C     2. band 0 with the debug check: refused at the start
      IPAR(1) = 0
      CALL VCINEW(CBMOD, N, M, NG, 78, H, RPAR, IPAR, IH, ISTAT)
      CALL CHECKI('VCINEW', ISTAT, 0, NBAD)
      CALL VCIBND(IH, 0, 1, ISTAT)
      CALL CHECKI('VCIBND', ISTAT, 0, NBAD)
      CALL VCIINM(IH, 0.0D0, Q0, P0, ISTAT)
      CALL CHECKI('VCIINM with band 0', ISTAT, 1, NBAD)
      CALL VCIMSG(IH, MSG)
      WRITE (*, '(2A)') ' ', MSG(1:150)
      CALL CHECKS('VCIMSG names the entry', MSG, 'L_qq(2, 1) =', NBAD)
      CALL VCIDEL(IH)
C     3. bit 64 without a continuous L is refused
      CALL VCINEW(CBMOD, N, M, NG, 64 + 2, H, RPAR, IPAR, IH, ISTAT)
      CALL CHECKI('VCINEW with IOPT = 66', ISTAT, 1, NBAD)
      IF (NBAD .GT. 0) STOP 1
      WRITE (*, '(A)') ' all checks passed'
      END
C
C     The chain: L = |V|**2/2 - sum over the N + 1 springs of
C     R**2/2 + R**4/4, R(0) = X(1), R(J) = X(J+1) - X(J), R(N) = -X(N).
      SUBROUTINE CBMOD(TASK, N, M, NG, Q, V, H, OUT, RPAR, IPAR, IERR)
      IMPLICIT NONE
      INTEGER TASK, N, M, NG, IPAR(*), IERR
      DOUBLE PRECISION Q(N), V(N), H, OUT(*), RPAR(*)
      DOUBLE PRECISION R(0:64), F(0:64), S, KJ
      INTEGER I, J, NN, LD, NB
      R(0) = Q(1)
      DO 5 J = 1, N - 1
        R(J) = Q(J + 1) - Q(J)
    5 CONTINUE
      R(N) = -Q(N)
      DO 6 J = 0, N
        F(J) = R(J) + R(J)**3
    6 CONTINUE
      IF (TASK .EQ. 10) THEN
        S = 0.0D0
        DO 10 I = 1, N
          S = S + 0.5D0 * V(I)**2
   10   CONTINUE
        DO 11 J = 0, N
          S = S - 0.5D0 * R(J)**2 - 0.25D0 * R(J)**4
   11   CONTINUE
        OUT(1) = S
      ELSE IF (TASK .EQ. 11) THEN
        DO 20 I = 1, N
          OUT(I) = F(I) - F(I - 1)
   20   CONTINUE
      ELSE IF (TASK .EQ. 12) THEN
        DO 30 I = 1, N
          OUT(I) = V(I)
   30   CONTINUE
      ELSE IF (TASK .EQ. 13) THEN
        IPAR(2) = IPAR(2) + 1
        NN = N * N
        DO 40 I = 1, 3 * NN
          OUT(I) = 0.0D0
   40   CONTINUE
        DO 41 I = 1, N
          OUT(I + N * (I - 1)) =
     &      -(2.0D0 + 3.0D0 * (R(I-1)**2 + R(I)**2))
          OUT(2 * NN + I + N * (I - 1)) = 1.0D0
          IF (I .LT. N) THEN
            KJ = 1.0D0 + 3.0D0 * R(I)**2
            OUT(I + N * I) = KJ
            OUT(I + 1 + N * (I - 1)) = KJ
          END IF
   41   CONTINUE
      ELSE IF (TASK .EQ. 18) THEN
C       band storage with the band VCIBND declared: IPAR(1) holds
C       it; IPAR(2) counts the calls (of TASK 13 too)
        IPAR(2) = IPAR(2) + 1
        LD = 2 * IPAR(1) + 1
        NB = LD * N
        DO 50 I = 1, 3 * NB
          OUT(I) = 0.0D0
   50   CONTINUE
        DO 51 J = 1, N
          OUT(IPAR(1) + 1 + LD * (J - 1)) =
     &      -(2.0D0 + 3.0D0 * (R(J-1)**2 + R(J)**2))
          OUT(2 * NB + IPAR(1) + 1 + LD * (J - 1)) = 1.0D0
          IF (J .LT. N .AND. IPAR(1) .GE. 1) THEN
            KJ = 1.0D0 + 3.0D0 * R(J)**2
            OUT(IPAR(1) + 2 + LD * (J - 1)) = KJ
            OUT(IPAR(1) + LD * J) = KJ
          END IF
   51   CONTINUE
      ELSE IF (TASK .EQ. 7) THEN
        DO 70 I = 1, N
          OUT(I) = 0.6D0 - Q(I)
          OUT(N + I) = 0.6D0 + Q(I)
   70   CONTINUE
      ELSE IF (TASK .EQ. 8) THEN
        DO 80 I = 1, N * NG
          OUT(I) = 0.0D0
   80   CONTINUE
        DO 81 I = 1, N
          OUT(I + N * (I - 1)) = -1.0D0
          OUT(I + N * (N + I - 1)) = 1.0D0
   81   CONTINUE
      ELSE IF (TASK .EQ. 9) THEN
C       H(Q, P) with P in V
        S = 0.0D0
        DO 90 I = 1, N
          S = S + 0.5D0 * V(I)**2
   90   CONTINUE
        DO 91 J = 0, N
          S = S + 0.5D0 * R(J)**2 + 0.25D0 * R(J)**4
   91   CONTINUE
        OUT(1) = S
      ELSE
        IERR = -999
      END IF
      END
