C     The paper's bouncing ellipse through vci's legacy entry points,
C     written as a Fortran 77 program: no modules, one EXTERNAL model
C     routine, explicit-shape arrays, integer status (see VCIRUN in
C     docs/C_API.md). Stops with code 1 if a number is off.
      PROGRAM ELL77
      IMPLICIT NONE
      EXTERNAL ELLMOD
      INTEGER N, M, NG, LTIMP
      PARAMETER (N = 3, M = 0, NG = 1, LTIMP = 10)
      DOUBLE PRECISION H, T0, Q0(N), Q1(N), T, Q(N), P(N), TIMP(LTIMP)
      DOUBLE PRECISION RPAR(4), QC(N), QD(N), T1REF, T2REF
      DOUBLE PRECISION TR, QR(N), PR(N)
      INTEGER IPAR(2), NIMP, ISTAT, IH, I, NBAD
      CHARACTER*300 MSG
C     First impacts at h = 1e-2 from the Fortran API (vci_integrator_t)
      PARAMETER (T1REF = 7.50564104356950312D-01)
      PARAMETER (T2REF = 1.15253289965270556D+00)
      DATA RPAR /1.0D0, 9.8D0, 1.0D0, 0.5D0/
      DATA QD /-3.0D0, 2.0D0, 0.0D0/
      NBAD = 0
      IPAR(1) = 0
      IPAR(2) = 0
      H = 1.0D-2
      QC(1) = ACOS(-1.0D0) / 2.0D0
      QC(2) = 0.0D0
      QC(3) = 3.5D0
      T0 = -0.5D0 * H
      DO 10 I = 1, N
        Q0(I) = QC(I) - 0.5D0 * H * QD(I)
        Q1(I) = QC(I) + 0.5D0 * H * QD(I)
   10 CONTINUE
C
C     1. One call: 200 steps with the analytic Hessian and gradients
      CALL VCIRUN(ELLMOD, N, M, NG, 3, H, T0, Q0, Q1, 200, T, Q, P,
     &            NIMP, TIMP, LTIMP, RPAR, IPAR, ISTAT, MSG)
      WRITE (*, '(A, I2, A, I3, A, F18.15)') ' VCIRUN: ISTAT =', ISTAT,
     &  '  impacts:', NIMP, '  first at t =', TIMP(1)
      CALL CHECKI('VCIRUN status', ISTAT, 0, NBAD)
      CALL CHECKI('VCIRUN impacts in 2 s', NIMP, 2, NBAD)
      CALL CHECKR('VCIRUN first impact', TIMP(1), T1REF, 1.0D-12, NBAD)
      CALL CHECKR('VCIRUN second impact', TIMP(2), T2REF, 1.0D-12,
     &            NBAD)
      CALL CHECKR('VCIRUN final time', T, 2.005D0, 1.0D-13, NBAD)
      TR = T
      DO 5 I = 1, N
        QR(I) = Q(I)
        PR(I) = P(I)
    5 CONTINUE
C
C     1b. The same run with a hostile routine (IPAR(2) = 1: after its
C         answer it overwrites TASK, N, M, NG, Q, V and H): the library
C         passes copies, so the run is the one above, bit for bit
      IPAR(2) = 1
      CALL VCIRUN(ELLMOD, N, M, NG, 3, H, T0, Q0, Q1, 200, T, Q, P,
     &            NIMP, TIMP, LTIMP, RPAR, IPAR, ISTAT, MSG)
      IPAR(2) = 0
      CALL CHECKI('hostile routine: status', ISTAT, 0, NBAD)
      CALL CHECKR('hostile routine: H unchanged', H, 1.0D-2, 0.0D0,
     &            NBAD)
      CALL CHECKR('hostile routine: final time', T, TR, 0.0D0, NBAD)
      DO 6 I = 1, N
        CALL CHECKR('hostile routine: same Q', Q(I), QR(I), 0.0D0,
     &              NBAD)
        CALL CHECKR('hostile routine: same P', P(I), PR(I), 0.0D0,
     &              NBAD)
    6 CONTINUE
C
C     1c. The fused task (IOPT bit 128: TASK 19 gives D1, D2, D3 and
C         the Hessian in one call, the same arithmetic): the run of 1,
C         bit for bit; and IPAR(1) = 1 makes TASK 19 fail as TASK 1
      CALL VCIRUN(ELLMOD, N, M, NG, 3 + 128, H, T0, Q0, Q1, 200, T, Q,
     &            P, NIMP, TIMP, LTIMP, RPAR, IPAR, ISTAT, MSG)
      CALL CHECKI('fused task: status', ISTAT, 0, NBAD)
      CALL CHECKI('fused task: impacts', NIMP, 2, NBAD)
      CALL CHECKR('fused task: final time', T, TR, 0.0D0, NBAD)
      DO 7 I = 1, N
        CALL CHECKR('fused task: same Q', Q(I), QR(I), 0.0D0, NBAD)
        CALL CHECKR('fused task: same P', P(I), PR(I), 0.0D0, NBAD)
    7 CONTINUE
      IPAR(1) = 1
      CALL VCIRUN(ELLMOD, N, M, NG, 3 + 128, H, T0, Q0, Q1, 200, T, Q,
     &            P, NIMP, TIMP, LTIMP, RPAR, IPAR, ISTAT, MSG)
      IPAR(1) = 0
      CALL CHECKI('fused task failing', ISTAT, 2, NBAD)
      IF (INDEX(MSG, 'TASK = 19') .EQ. 0) THEN
        WRITE (*, *) 'FAIL: the message does not name TASK = 19'
        NBAD = NBAD + 1
      END IF
      CALL VCIRUN(ELLMOD, N, M, NG, 8 + 128, H, T0, Q0, Q1, 200, T, Q,
     &            P, NIMP, TIMP, LTIMP, RPAR, IPAR, ISTAT, MSG)
      CALL CHECKI('TASK 19 with a continuous L', ISTAT, 1, NBAD)
      CALL VCIRUN(ELLMOD, N, M, NG, 3 + 16 + 128, H, T0, Q0, Q1, 200,
     &            T, Q, P, NIMP, TIMP, LTIMP, RPAR, IPAR, ISTAT, MSG)
      CALL CHECKI('TASK 19 with a separable L', ISTAT, 1, NBAD)
C
C     2. The handle interface, differenced Jacobians (IOPT = 0):
C        forward 200 steps, then backward to the pair
      CALL VCINEW(ELLMOD, N, M, NG, 0, H, RPAR, IPAR, IH, ISTAT)
      CALL CHECKI('VCINEW', ISTAT, 0, NBAD)
      CALL VCITOL(IH, 0.0D0, 1.0D-12, 30, ISTAT)
      CALL CHECKI('VCITOL', ISTAT, 0, NBAD)
      CALL VCIINP(IH, T0, Q0, Q1, ISTAT)
      CALL CHECKI('VCIINP', ISTAT, 0, NBAD)
      CALL VCIADV(IH, 200, 1, T, Q, P, NIMP, TIMP, LTIMP, ISTAT)
      CALL CHECKI('VCIADV forward', ISTAT, 0, NBAD)
      CALL CHECKI('VCIADV forward impacts', NIMP, 2, NBAD)
      CALL CHECKR('VCIADV first impact', TIMP(1), T1REF, 1.0D-8, NBAD)
      CALL VCIADV(IH, 200, -1, T, Q, P, NIMP, TIMP, LTIMP, ISTAT)
      CALL CHECKI('VCIADV backward', ISTAT, 0, NBAD)
      CALL CHECKI('VCIADV backward impacts', NIMP, 2, NBAD)
      CALL CHECKR('VCIADV back to t1', T, T0 + H, 1.0D-13, NBAD)
      DO 20 I = 1, N
        CALL CHECKR('VCIADV back to q1', Q(I), Q1(I), 1.0D-8, NBAD)
   20 CONTINUE
C     the hamiltonian condition needs the energy task (IOPT bit 4)
      CALL VCIENG(IH, 1, ISTAT)
      CALL CHECKI('VCIENG without energy', ISTAT, 1, NBAD)
      CALL VCIADV(IH, 1, 2, T, Q, P, NIMP, TIMP, LTIMP, ISTAT)
      CALL CHECKI('VCIADV bad direction', ISTAT, 1, NBAD)
      CALL VCIMSG(IH, MSG)
      WRITE (*, '(2A)') ' VCIMSG: ', MSG(1:60)
      CALL VCIDEL(IH)
      CALL CHECKI('VCIDEL clears IH', IH, 0, NBAD)
      CALL VCIADV(IH, 1, 1, T, Q, P, NIMP, TIMP, LTIMP, ISTAT)
      CALL CHECKI('VCIADV on a deleted handle', ISTAT, 1, NBAD)
C
C     3. A model routine that fails (IPAR(1) = 1: TASK 1 from the
C        start) gives ISTAT = 2 and a message naming the task
      IPAR(1) = 1
      CALL VCIRUN(ELLMOD, N, M, NG, 3, H, T0, Q0, Q1, 200, T, Q, P,
     &            NIMP, TIMP, LTIMP, RPAR, IPAR, ISTAT, MSG)
      WRITE (*, '(2A)') ' failing model: ', MSG(1:110)
      CALL CHECKI('failing model', ISTAT, 2, NBAD)
      IF (INDEX(MSG, 'TASK = 1') .EQ. 0) THEN
        WRITE (*, *) 'FAIL: the message does not name TASK = 1'
        NBAD = NBAD + 1
      END IF
C
      IF (NBAD .NE. 0) THEN
        WRITE (*, '(A, I3, A)') ' legacy ellipse:', NBAD, ' FAILED'
        STOP 1
      END IF
      WRITE (*, '(A)') ' legacy ellipse: all checks passed'
      END
C
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
C     The ellipse: q = (theta, x, y), midpoint L_d with gravity, floor
C     g = y - phi(theta). RPAR = (mass, gravity, a, b). IPAR(1) = 1
C     makes TASK 1 and 19 fail (to test the error path); TASK 19 is
C     TASKs 1 to 4 in one call (IOPT bit 128); IPAR(2) = 1 makes it
C     overwrite every input argument after answering (ELLBAD).
      SUBROUTINE ELLMOD(TASK, N, M, NG, Q, V, H, OUT, RPAR, IPAR, IERR)
      IMPLICIT NONE
      INTEGER TASK, N, M, NG, IPAR(*), IERR, I
      DOUBLE PRECISION Q(N), V(N), H, OUT(*), RPAR(*)
      DOUBLE PRECISION AM, G, A, B, AI, S, C, PHI
      AM = RPAR(1)
      G = RPAR(2)
      A = RPAR(3)
      B = RPAR(4)
      AI = AM * (A**2 + B**2) / 4.0D0
      IF (TASK .EQ. 1) THEN
        IF (IPAR(1) .EQ. 1) THEN
          IERR = 3
          RETURN
        END IF
        OUT(1) = -AI * (V(1) - Q(1)) / H
        OUT(2) = -AM * (V(2) - Q(2)) / H
        OUT(3) = -AM * (V(3) - Q(3)) / H - 0.5D0 * H * AM * G
      ELSE IF (TASK .EQ. 2) THEN
        OUT(1) = AI * (V(1) - Q(1)) / H
        OUT(2) = AM * (V(2) - Q(2)) / H
        OUT(3) = AM * (V(3) - Q(3)) / H - 0.5D0 * H * AM * G
      ELSE IF (TASK .EQ. 3) THEN
        OUT(1) = -0.5D0 * (AI * (V(1) - Q(1))**2 + AM * ((V(2) - Q(2))
     &     **2 + (V(3) - Q(3))**2)) / H**2 - 0.5D0 * AM * G * (Q(3)
     &     + V(3))
      ELSE IF (TASK .EQ. 4) THEN
        DO 10 I = 1, 9
          OUT(I) = 0.0D0
   10   CONTINUE
        OUT(1) = -AI / H
        OUT(5) = -AM / H
        OUT(9) = -AM / H
      ELSE IF (TASK .EQ. 19) THEN
        IF (IPAR(1) .EQ. 1) THEN
          IERR = 3
          RETURN
        END IF
        OUT(1) = -AI * (V(1) - Q(1)) / H
        OUT(2) = -AM * (V(2) - Q(2)) / H
        OUT(3) = -AM * (V(3) - Q(3)) / H - 0.5D0 * H * AM * G
        OUT(4) = AI * (V(1) - Q(1)) / H
        OUT(5) = AM * (V(2) - Q(2)) / H
        OUT(6) = AM * (V(3) - Q(3)) / H - 0.5D0 * H * AM * G
        OUT(7) = -0.5D0 * (AI * (V(1) - Q(1))**2 + AM * ((V(2) - Q(2))
     &     **2 + (V(3) - Q(3))**2)) / H**2 - 0.5D0 * AM * G * (Q(3)
     &     + V(3))
        DO 20 I = 8, 16
          OUT(I) = 0.0D0
   20   CONTINUE
        OUT(8) = -AI / H
        OUT(12) = -AM / H
        OUT(16) = -AM / H
      ELSE IF (TASK .EQ. 7) THEN
        S = SIN(Q(1))
        C = COS(Q(1))
        OUT(1) = Q(3) - SQRT(A**2 * S**2 + B**2 * C**2)
      ELSE IF (TASK .EQ. 8) THEN
        S = SIN(Q(1))
        C = COS(Q(1))
        PHI = SQRT(A**2 * S**2 + B**2 * C**2)
        OUT(1) = -(A**2 - B**2) * S * C / PHI
        OUT(2) = 0.0D0
        OUT(3) = 1.0D0
      ELSE
        IERR = 99
      END IF
      IF (IPAR(2) .EQ. 1) CALL ELLBAD(TASK, N, M, NG, Q, V, H)
      END
C
C     What a careless routine might do to its inputs: N and H doubled,
C     M and NG made huge, TASK, Q and V overwritten (N last, since Q
C     and V are dimensioned by it).
      SUBROUTINE ELLBAD(TASK, N, M, NG, Q, V, H)
      IMPLICIT NONE
      INTEGER TASK, N, M, NG, I
      DOUBLE PRECISION Q(N), V(N), H
      DO 10 I = 1, N
        Q(I) = -1.0D300
        V(I) = 7.0D0
   10 CONTINUE
      H = 2.0D0 * H
      TASK = 99
      M = 100000
      NG = 100000
      N = 2 * N + 1000
      END
