C     The walled pendulum as a separable model through vci's legacy
C     entry points (IOPT bit 16, TASKs 14-17, the explicit composition
C     of order 6: VCISCH(IH, 4, 6, ...)), written as a Fortran 77
C     program. V = -G COS(TH) (G = 9.8), M = 1, walls TW - TH >= 0,
C     TH + TW >= 0 (TW = 1 rad), TH(0) = 0, TH'(0) = 4, 10 s. The
C     expected numbers come from vci_separable_ref (the same runs with
C     the Fortran separable scene, and the exact solution), read from
C     separable_ref.txt. Stops with code 1 if a number is off.
      PROGRAM SEPW
      IMPLICIT NONE
      EXTERNAL SWMOD
      INTEGER N, M, NG, LTIMP
      PARAMETER (N = 1, M = 0, NG = 2, LTIMP = 40)
      DOUBLE PRECISION HREF(3), QREF(3), PREF(3), QEX, PEX, ERR(3)
      DOUBLE PRECISION T, Q(N), P(N), TIMP(LTIMP), RPAR(2), Q0(N)
      DOUBLE PRECISION P0(N), SLOPE, WORST
      INTEGER IPAR(1), NIMP, NREF(3), NEX, ISTAT, IH, NBAD, K, J
      INTEGER IOPT(2), NSTEP, IPASS
      CHARACTER*300 MSG
      DATA RPAR /9.8D0, 1.0D0/
C     19 = 16 (separable) + 2 (gap gradients) + 1 (Hessian of V);
C     51 = the same with M given densely (TASK 17: N*N numbers)
      DATA IOPT /19, 51/
      NBAD = 0
      Q0(1) = 0.0D0
      P0(1) = 4.0D0
      IPAR(1) = 0
      OPEN (UNIT = 10, FILE = 'separable_ref.txt', STATUS = 'OLD',
     &      ERR = 900)
      DO 5 J = 1, 3
        READ (10, *, ERR = 900, END = 900) HREF(J), QREF(J), PREF(J),
     &    NREF(J)
    5 CONTINUE
      READ (10, *, ERR = 900, END = 900) QEX, PEX, NEX
      CLOSE (10)
C
C     1. Order 6 at three step sizes, M diagonal and dense: the same
C        bits as the Fortran separable scene, and order 6 against the
C        exact state (halving h divides the error by 2**6)
      DO 20 K = 1, 2
        DO 10 J = 1, 3
          CALL VCINEW(SWMOD, N, M, NG, IOPT(K), HREF(J), RPAR, IPAR,
     &                IH, ISTAT)
          CALL CHECKI('VCINEW', ISTAT, 0, NBAD)
          CALL VCISCH(IH, 4, 6, ISTAT)
          CALL CHECKI('VCISCH composition 6', ISTAT, 0, NBAD)
          CALL VCIINM(IH, 0.0D0, Q0, P0, ISTAT)
          CALL CHECKI('VCIINM', ISTAT, 0, NBAD)
          NSTEP = NINT(10.0D0 / HREF(J))
          CALL VCIADV(IH, NSTEP, 1, T, Q, P, NIMP, TIMP, LTIMP, ISTAT)
          IF (ISTAT .NE. 0) THEN
            CALL VCIMSG(IH, MSG)
            WRITE (*, '(2A)') ' VCIADV: ', MSG(1:200)
          END IF
          CALL CHECKI('VCIADV', ISTAT, 0, NBAD)
          WRITE (*, '(A, I3, A, F6.3, A, I3, A, 2ES10.2)') ' IOPT =',
     &      IOPT(K), '  h =', HREF(J), '  impacts:', NIMP,
     &      '  |q - exact|, |p - exact|:', ABS(Q(1) - QEX),
     &      ABS(P(1) - PEX)
          CALL CHECKI('impacts = Fortran', NIMP, NREF(J), NBAD)
          CALL CHECKI('impacts = exact', NIMP, NEX, NBAD)
          CALL CHECKR('q = Fortran, same bits', Q(1), QREF(J), 0.0D0,
     &                NBAD)
          CALL CHECKR('p = Fortran, same bits', P(1), PREF(J), 0.0D0,
     &                NBAD)
          ERR(J) = MAX(ABS(Q(1) - QEX), ABS(P(1) - PEX))
          CALL VCIDEL(IH)
   10   CONTINUE
C       over the two octaves (one alone scatters: 7.15, 5.28)
        SLOPE = LOG(ERR(1) / ERR(3)) / LOG(HREF(1) / HREF(3))
        WRITE (*, '(A, F6.2)') ' observed order: ', SLOPE
        CALL CHECKR('order 6', SLOPE, 6.0D0, 0.5D0, NBAD)
   20 CONTINUE
C     the model checker passes the separable model (its derived L)
      CALL VCINEW(SWMOD, N, M, NG, 19, 0.05D0, RPAR, IPAR, IH, ISTAT)
      Q(1) = 0.3D0
      P(1) = 1.7D0
      CALL VCICHK(IH, Q, P, 0.05D0, 0.0D0, IPASS, WORST, ISTAT)
      CALL CHECKI('VCICHK', ISTAT, 0, NBAD)
      CALL CHECKI('VCICHK verdict', IPASS, 1, NBAD)
      CALL VCIDEL(IH)
C
C     2. Refusals with ISTAT = 1 and a message saying why
      CALL VCINEW(SWMOD, N, 1, NG, 19, 0.05D0, RPAR, IPAR, IH, ISTAT)
      CALL CHECKI('VCINEW with M = 1', ISTAT, 1, NBAD)
      CALL CHECKI('VCINEW with M = 1: IH', IH, 0, NBAD)
      CALL VCIMSG(0, MSG)
      WRITE (*, '(2A)') ' M = 1: ', MSG(1:160)
      CALL CHECKS('M = 1 message', MSG, 'nonholonomic', NBAD)
      CALL VCINEW(SWMOD, N, M, NG, 17, 0.05D0, RPAR, IPAR, IH, ISTAT)
      CALL CHECKI('VCINEW without gap gradients', ISTAT, 1, NBAD)
      CALL VCIMSG(0, MSG)
      CALL CHECKS('no gap gradients message', MSG, 'TASK 8', NBAD)
      CALL VCINEW(SWMOD, N, M, NG, 27, 0.05D0, RPAR, IPAR, IH, ISTAT)
      CALL CHECKI('VCINEW with bits 16 and 8', ISTAT, 1, NBAD)
C     a mass that is not positive (IPAR(1) = 1: TASK 17 gives -1)
      IPAR(1) = 1
      CALL VCINEW(SWMOD, N, M, NG, 19, 0.05D0, RPAR, IPAR, IH, ISTAT)
      CALL CHECKI('VCINEW with M = -1', ISTAT, 1, NBAD)
      CALL VCIMSG(0, MSG)
      WRITE (*, '(2A)') ' mass -1: ', MSG(1:160)
      CALL CHECKS('mass message', MSG, 'TASK 17', NBAD)
C     a failing gradient (IPAR(1) = 2: TASK 15 gives IERR = -5 once Q
C     has passed 0.5) stops the run with ISTAT = 2 naming TASK 15
      IPAR(1) = 2
      CALL VCINEW(SWMOD, N, M, NG, 19, 0.05D0, RPAR, IPAR, IH, ISTAT)
      CALL CHECKI('VCINEW', ISTAT, 0, NBAD)
      CALL VCISCH(IH, 4, 4, ISTAT)
      CALL VCIINM(IH, 0.0D0, Q0, P0, ISTAT)
      CALL VCIADV(IH, 200, 1, T, Q, P, NIMP, TIMP, LTIMP, ISTAT)
      CALL CHECKI('failing TASK 15', ISTAT, 2, NBAD)
      CALL VCIMSG(IH, MSG)
      WRITE (*, '(2A)') ' failing TASK 15: ', MSG(1:160)
      CALL CHECKS('failing TASK 15 message', MSG, 'TASK = 15', NBAD)
      CALL VCIDEL(IH)
C
      IF (NBAD .NE. 0) THEN
        WRITE (*, '(A, I3, A)') ' legacy separable:', NBAD, ' FAILED'
        STOP 1
      END IF
      WRITE (*, '(A)') ' legacy separable: all checks passed'
      STOP
  900 WRITE (*, '(A)') ' FAIL: cannot read separable_ref.txt'
      STOP 1
      END
C
C     The walled pendulum as a separable model: V(Q) = -G COS(Q), M =
C     RPAR(2)-independent 1 (diagonal, or 1 x 1 dense: the same
C     number). RPAR = (gravity, wall angle). IPAR(1) = 1: TASK 17
C     gives M = -1; 2: TASK 15 fails (IERR = -5) once Q has passed 0.5.
      SUBROUTINE SWMOD(TASK, N, M, NG, Q, V, H, OUT, RPAR, IPAR, IERR)
      IMPLICIT NONE
      INTEGER TASK, N, M, NG, IPAR(*), IERR
      DOUBLE PRECISION Q(N), V(N), H, OUT(*), RPAR(*)
      DOUBLE PRECISION G, TW
      G = RPAR(1)
      TW = RPAR(2)
      IF (TASK .EQ. 14) THEN
        OUT(1) = -G * COS(Q(1))
      ELSE IF (TASK .EQ. 15) THEN
        IF (IPAR(1) .EQ. 2 .AND. Q(1) .GT. 0.5D0) THEN
          IERR = -5
          RETURN
        END IF
        OUT(1) = G * SIN(Q(1))
      ELSE IF (TASK .EQ. 16) THEN
        OUT(1) = G * COS(Q(1))
      ELSE IF (TASK .EQ. 17) THEN
        OUT(1) = 1.0D0
        IF (IPAR(1) .EQ. 1) OUT(1) = -1.0D0
      ELSE IF (TASK .EQ. 7) THEN
        OUT(1) = TW - Q(1)
        OUT(2) = Q(1) + TW
      ELSE IF (TASK .EQ. 8) THEN
        OUT(1) = -1.0D0
        OUT(2) = 1.0D0
      ELSE
        IERR = -999
      END IF
      END
