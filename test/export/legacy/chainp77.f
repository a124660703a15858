C     A declared sparse Hessian pattern through vci's legacy entry
C     points (VCIPAT, issue 28), as a Fortran 77 program: the FPU-beta
C     chain of chainb77.f (N = 20 between walls |X(I)| <= 0.6,
C     midpoint, h = 0.01, 100 steps, hamiltonian impacts, TASK 13).
C     With the sparse solver (VCI_SPARSE): 1. the tridiagonal pattern,
C     debug check off and on, against the dense run: the same impacts
C     and end state to 1E-9 (each solve meets rtol 1E-12); 2. the
C     pattern withdrawn (NNZ = -1): the dense run bit for bit; and the
C     tridiagonal pattern with TASK 20 alone (IOPT bit 256, no TASK 13:
C     Newton's matrix assembled in the pattern), equal to dense to
C     1E-9 with TASK 20 called (counted in IPAR(1)); 3. the
C     diagonal alone with the check: the run fails with ISTAT = 1 and
C     VCIMSG names the entry (2, 1); 4. bad patterns (ICOLP(N+1) not
C     NNZ + 1, ICOLP(1) not 1, a row outside 1..N, rows unsorted or
C     repeated)
C     refused with ISTAT = 1 and a message naming the array element.
C     Without it: VCIPAT refuses with ISTAT = 1 naming VCI_SPARSE, and
C     NNZ = -1 is accepted. The last line says which branch ran (the
C     ctest checks it against the build). CHECKI, CHECKR, CHECKS:
C     checks77.f. Stops with code 1 if anything is off.
      PROGRAM CHAINP
      IMPLICIT NONE
      EXTERNAL CPMOD
      INTEGER N, M, NG, LTIMP, MAXNZ
      PARAMETER (N = 20, M = 0, NG = 40, LTIMP = 400, MAXNZ = 3 * N)
      DOUBLE PRECISION H, T, Q(N), P(N), QD(N), PD(N), TIMP(LTIMP)
      DOUBLE PRECISION Q0(N), P0(N), RPAR(1), PI, DQ, DP
      INTEGER IPAR(1), NIMP, NIMPD, ISTAT, IH, NBAD, I, K, NNZ
      INTEGER ICOLP(N + 1), IROW(MAXNZ), IDIAG(N + 1), IRD(N), ITMP
      CHARACTER*300 MSG
      NBAD = 0
      H = 1.0D-2
      PI = ACOS(-1.0D0)
      DO 5 I = 1, N
        Q0(I) = 0.24D0 * SIN(2 * PI * I / 21.0D0)
        P0(I) = 1.2D0 * SIN(3 * PI * I / 21.0D0)
     &        + 0.8D0 * SIN(PI * I / 21.0D0)
    5 CONTINUE
C     the tridiagonal pattern, 1-based compressed columns, and the
C     diagonal alone
      NNZ = 0
      DO 8 K = 1, N
        ICOLP(K) = NNZ + 1
        IDIAG(K) = K
        IRD(K) = K
        DO 7 I = MAX(1, K - 1), MIN(N, K + 1)
          NNZ = NNZ + 1
          IROW(NNZ) = I
    7   CONTINUE
    8 CONTINUE
      ICOLP(N + 1) = NNZ + 1
      IDIAG(N + 1) = N + 1
C
C     without the sparse solver: refused naming the option
      CALL VCINEW(CPMOD, N, M, NG, 15, H, RPAR, IPAR, IH, ISTAT)
      CALL CHECKI('VCINEW', ISTAT, 0, NBAD)
      CALL VCIPAT(IH, NNZ, ICOLP, IROW, 0, ISTAT)
      IF (ISTAT .NE. 0) THEN
        CALL VCIMSG(IH, MSG)
        WRITE (*, '(2A)') ' ', MSG(1:160)
        CALL CHECKI('VCIPAT without VCI_SPARSE', ISTAT, 1, NBAD)
        CALL CHECKS('VCIMSG names the option', MSG,
     &    'built without the sparse solver (CMake VCI_SPARSE=OFF', NBAD)
        CALL VCIPAT(IH, -1, ICOLP, IROW, 0, ISTAT)
        CALL CHECKI('VCIPAT NNZ = -1', ISTAT, 0, NBAD)
        CALL VCIDEL(IH)
        IF (NBAD .GT. 0) STOP 1
        WRITE (*, '(A)') ' no sparse solver: refusal checked'
        STOP
      END IF
      CALL VCIDEL(IH)
C
C     1., 2. dense (K = 1), tridiagonal with the check off (K = 2) and
C     on (K = 3), declared and withdrawn (K = 4), TASK 20 alone (K = 5)
      DO 20 K = 1, 5
        IPAR(1) = 0
        IF (K .LT. 5) THEN
          CALL VCINEW(CPMOD, N, M, NG, 15, H, RPAR, IPAR, IH, ISTAT)
        ELSE
          CALL VCINEW(CPMOD, N, M, NG, 270, H, RPAR, IPAR, IH, ISTAT)
        END IF
        CALL CHECKI('VCINEW', ISTAT, 0, NBAD)
        IF (K .GE. 2) THEN
          CALL VCIPAT(IH, NNZ, ICOLP, IROW, MOD(K - 2, 3), ISTAT)
          CALL CHECKI('VCIPAT', ISTAT, 0, NBAD)
        END IF
        IF (K .EQ. 4) THEN
          CALL VCIPAT(IH, -1, ICOLP, IROW, 0, ISTAT)
          CALL CHECKI('VCIPAT NNZ = -1', ISTAT, 0, NBAD)
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
          NIMPD = NIMP
          DO 10 I = 1, N
            QD(I) = Q(I)
            PD(I) = P(I)
   10     CONTINUE
        ELSE
          DQ = 0.0D0
          DP = 0.0D0
          DO 15 I = 1, N
            DQ = MAX(DQ, ABS(Q(I) - QD(I)))
            DP = MAX(DP, ABS(P(I) - PD(I)))
   15     CONTINUE
          WRITE (*, '(A, I2, A, 2I4, A, 2ES10.2)') ' run', K,
     &      ': impacts dense, sparse:', NIMPD, NIMP,
     &      '  |dq|, |dp|:', DQ, DP
          CALL CHECKI('sparse impacts = dense', NIMP, NIMPD, NBAD)
          IF (K .EQ. 5) THEN
            WRITE (*, '(A, I6)') ' TASK 20 calls:', IPAR(1)
            IF (IPAR(1) .LT. 1)
     &        CALL CHECKI('TASK 20 called', 0, 1, NBAD)
          END IF
          IF (K .NE. 4) THEN
            CALL CHECKR('sparse q - dense q', DQ, 0.0D0, 1.0D-9, NBAD)
            CALL CHECKR('sparse p - dense p', DP, 0.0D0, 1.0D-9, NBAD)
          ELSE
            CALL CHECKR('withdrawn q - dense q', DQ, 0.0D0, 0.0D0,
     &        NBAD)
            CALL CHECKR('withdrawn p - dense p', DP, 0.0D0, 0.0D0,
     &        NBAD)
          END IF
        END IF
   20 CONTINUE
      IF (NIMPD .LT. 10) CALL CHECKI('dense impacts >= 10', 0, 1, NBAD)
C
C     3. the diagonal alone with the debug check: the run fails
      CALL VCINEW(CPMOD, N, M, NG, 15, H, RPAR, IPAR, IH, ISTAT)
      CALL CHECKI('VCINEW', ISTAT, 0, NBAD)
      CALL VCIPAT(IH, N, IDIAG, IRD, 1, ISTAT)
      CALL CHECKI('VCIPAT diagonal', ISTAT, 0, NBAD)
      CALL VCIINM(IH, 0.0D0, Q0, P0, ISTAT)
      IF (ISTAT .EQ. 0)
     &  CALL VCIADV(IH, 1, 1, T, Q, P, NIMP, TIMP, LTIMP, ISTAT)
      CALL CHECKI('diagonal pattern with the check', ISTAT, 1, NBAD)
      CALL VCIMSG(IH, MSG)
      WRITE (*, '(2A)') ' ', MSG(1:160)
      CALL CHECKS('VCIMSG names the entry', MSG,
     &  'nonzero at (2, 1) outside the Hessian bandwidth', NBAD)
C
C     4. bad patterns, on the same handle
      CALL VCIPAT(IH, NNZ - 1, ICOLP, IROW, 0, ISTAT)
      CALL VCIMSG(IH, MSG)
      CALL CHECKI('VCIPAT NNZ - 1', ISTAT, 1, NBAD)
      CALL CHECKS('VCIMSG: ICOLP(N+1)', MSG, 'ICOLP(N+1) = 59, not NNZ',
     &  NBAD)
      ICOLP(1) = 0
      CALL VCIPAT(IH, NNZ, ICOLP, IROW, 0, ISTAT)
      CALL VCIMSG(IH, MSG)
      CALL CHECKI('VCIPAT ICOLP(1) = 0', ISTAT, 1, NBAD)
      CALL CHECKS('VCIMSG: ICOLP(1)', MSG, 'ICOLP(1) = 0, not 1', NBAD)
      ICOLP(1) = 1
      IROW(NNZ) = N + 1
      CALL VCIPAT(IH, NNZ, ICOLP, IROW, 0, ISTAT)
      CALL VCIMSG(IH, MSG)
      CALL CHECKI('VCIPAT row N + 1', ISTAT, 1, NBAD)
      CALL CHECKS('VCIMSG: IROW', MSG, 'IROW(58) = 21 (column 20) is '
     &  // 'outside 1..20', NBAD)
      IROW(NNZ) = N
      ITMP = IROW(4)
      IROW(4) = IROW(5)
      IROW(5) = ITMP
      CALL VCIPAT(IH, NNZ, ICOLP, IROW, 0, ISTAT)
      CALL VCIMSG(IH, MSG)
      WRITE (*, '(2A)') ' ', MSG(1:160)
      CALL CHECKI('VCIPAT unsorted', ISTAT, 1, NBAD)
      CALL CHECKS('VCIMSG: unsorted', MSG, 'the rows of column 2 are '
     &  // 'not strictly increasing at IROW(5)', NBAD)
      IROW(5) = IROW(4)
      CALL VCIPAT(IH, NNZ, ICOLP, IROW, 0, ISTAT)
      CALL VCIMSG(IH, MSG)
      CALL CHECKI('VCIPAT repeated row', ISTAT, 1, NBAD)
      CALL CHECKS('VCIMSG: repeated', MSG, 'the rows of column 2 are '
     &  // 'not strictly increasing at IROW(5) = 3', NBAD)
      CALL VCIDEL(IH)
      IF (NBAD .GT. 0) STOP 1
      WRITE (*, '(A)') ' sparse runs checked'
      END
C
C     The chain of chainb77.f: L = |V|**2/2 - sum over the N + 1 springs
C     of R**2/2 + R**4/4, R(0) = X(1), R(J) = X(J+1) - X(J), R(N) = -X(N).
      SUBROUTINE CPMOD(TASK, N, M, NG, Q, V, H, OUT, RPAR, IPAR, IERR)
      IMPLICIT NONE
      INTEGER TASK, N, M, NG, IPAR(*), IERR
      DOUBLE PRECISION Q(N), V(N), H, OUT(*), RPAR(*)
      DOUBLE PRECISION R(0:64), F(0:64), S, KJ
      INTEGER I, J, NN, K, NZ
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
      ELSE IF (TASK .EQ. 20) THEN
C       the blocks in the tridiagonal pattern's order (column J: rows
C       J-1, J, J+1 within 1..N), L_qq, L_qv, L_vv one after the other
        IPAR(1) = IPAR(1) + 1
        NZ = 3 * N - 2
        K = 0
        DO 51 J = 1, N
          DO 50 I = MAX(1, J - 1), MIN(N, J + 1)
            K = K + 1
            OUT(NZ + K) = 0.0D0
            IF (I .EQ. J) THEN
              OUT(K) = -(2.0D0 + 3.0D0 * (R(I-1)**2 + R(I)**2))
              OUT(2 * NZ + K) = 1.0D0
            ELSE
              OUT(K) = 1.0D0 + 3.0D0 * R(MIN(I, J))**2
              OUT(2 * NZ + K) = 0.0D0
            END IF
   50     CONTINUE
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
