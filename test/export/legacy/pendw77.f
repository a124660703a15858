C     The walled pendulum as a continuous Lagrangian through vci's
C     legacy entry points (IOPT bit 8, TASKs 10-13, VCISCH), written as
C     a Fortran 77 program. L = TH'**2/2 + G COS(TH) (m = l = 1, G =
C     9.8), walls G1 = TW - TH >= 0, G2 = TH + TW >= 0 (TW = 1 rad),
C     TH(0) = 0, TH'(0) = 4, h = 0.05, 200 steps (10 s), lobatto with
C     s = 4 and the hamiltonian impact condition. The expected state
C     and impact count come from pendw77_ref.f90 (the exact solution,
C     test/support/vci_ref_pendulum_walls.f90), read from the file
C     pendw77_ref.txt. Stops with code 1 if a number is off.
      PROGRAM PENDW
      IMPLICIT NONE
      EXTERNAL PWMOD
      INTEGER N, M, NG, LTIMP, NSTG
      PARAMETER (N = 1, M = 0, NG = 2, LTIMP = 40, NSTG = 4)
      DOUBLE PRECISION H, T, Q(N), P(N), TIMP(LTIMP), RPAR(2)
      DOUBLE PRECISION TREF, QREF, PREF, Q0(N), P0(N), T1, Q1(N), P1(N)
      INTEGER IPAR(1), NIMP, NREF, ISTAT, IH, NBAD, K, IOPT(4), IPASS
      INTEGER NSPL, MOSTSP
      DOUBLE PRECISION WORST
      CHARACTER*300 MSG
      DATA RPAR /9.8D0, 1.0D0/
C     all optional TASKs (Hessians, gap gradients, H); only L, dL/dq,
C     dL/dv and gaps; all declared but TASKs 13 and 9 answered "not
C     provided" (IPAR(1) = 5); all, from a routine that overwrites its
C     inputs after answering (IPAR(1) = 9): the run must be the first
      DATA IOPT /15, 8, 15, 15/
      NBAD = 0
      H = 5.0D-2
      Q0(1) = 0.0D0
      P0(1) = 4.0D0
      OPEN (UNIT = 10, FILE = 'pendw77_ref.txt', STATUS = 'OLD',
     &      ERR = 900)
      READ (10, *, ERR = 900, END = 900) TREF, QREF, PREF, NREF
      CLOSE (10)
C
C     1. The run, three ways of supplying the optional TASKs
      DO 10 K = 1, 4
        IPAR(1) = 0
        IF (K .EQ. 3) IPAR(1) = 5
        IF (K .EQ. 4) IPAR(1) = 9
        CALL VCINEW(PWMOD, N, M, NG, IOPT(K), H, RPAR, IPAR, IH,
     &              ISTAT)
        CALL CHECKI('VCINEW', ISTAT, 0, NBAD)
        CALL VCISCH(IH, 3, NSTG, ISTAT)
        CALL CHECKI('VCISCH lobatto', ISTAT, 0, NBAD)
        CALL VCITOL(IH, 0.0D0, 1.0D-15, 30, ISTAT)
        CALL CHECKI('VCITOL', ISTAT, 0, NBAD)
        CALL VCIENG(IH, 1, ISTAT)
        CALL CHECKI('VCIENG hamiltonian', ISTAT, 0, NBAD)
        CALL VCIINM(IH, 0.0D0, Q0, P0, ISTAT)
        CALL CHECKI('VCIINM', ISTAT, 0, NBAD)
        CALL VCIADV(IH, 200, 1, T, Q, P, NIMP, TIMP, LTIMP, ISTAT)
        IF (ISTAT .NE. 0) THEN
          CALL VCIMSG(IH, MSG)
          WRITE (*, '(2A)') ' VCIADV: ', MSG(1:200)
        END IF
        CALL CHECKI('VCIADV', ISTAT, 0, NBAD)
        WRITE (*, '(A, I3, A, I3, A, 2ES10.2)') ' IOPT =', IOPT(K),
     &    '  impacts:', NIMP, '  |q - exact|, |p - exact|:',
     &    ABS(Q(1) - QREF), ABS(P(1) - PREF)
        CALL CHECKI('impacts = exact count', NIMP, NREF, NBAD)
        CALL CHECKI('impacts in 10 s', NIMP, 18, NBAD)
        CALL CHECKR('final time', T, TREF, 1.0D-12, NBAD)
C       lobatto s = 4 (order 8) is ~1e-11 from exact at h = 0.05
C       (docs/SCHEMES.md); 1e-9 leaves room for round-off, not for
C       a lower order (s = 3 is ~3e-8 off)
        CALL CHECKR('theta = exact', Q(1), QREF, 1.0D-9, NBAD)
        CALL CHECKR('p = exact', P(1), PREF, 1.0D-9, NBAD)
        IF (K .EQ. 1) THEN
          T1 = T
          Q1(1) = Q(1)
          P1(1) = P(1)
        END IF
        IF (K .EQ. 4) THEN
          CALL CHECKR('hostile routine: same t', T, T1, 0.0D0, NBAD)
          CALL CHECKR('hostile routine: same q', Q(1), Q1(1), 0.0D0,
     &                NBAD)
          CALL CHECKR('hostile routine: same p', P(1), P1(1), 0.0D0,
     &                NBAD)
        END IF
        CALL VCIDEL(IH)
   10 CONTINUE
C
C     2. Bad input. A routine without dL/dv (IPAR(1) = 3: TASK 12
C        answered "not provided") is refused by VCINEW, naming it
      IPAR(1) = 3
      CALL VCINEW(PWMOD, N, M, NG, 8, H, RPAR, IPAR, IH, ISTAT)
      CALL CHECKI('VCINEW without dL/dv', ISTAT, 1, NBAD)
      CALL CHECKI('VCINEW without dL/dv: IH', IH, 0, NBAD)
      CALL VCIMSG(0, MSG)
      WRITE (*, '(2A)') ' no dL/dv: ', MSG(1:160)
      CALL CHECKS('no dL/dv names dl_dv', MSG, 'dl_dv', NBAD)
      CALL CHECKS('no dL/dv names TASK 12', MSG, 'TASK = 12', NBAD)
      IPAR(1) = 0
C     unknown IOPT bits (16, 32: separable, sepw77.f; 64: banded
C     Hessians, chainb77.f; 128: the fused TASK 19, ellipse77.f; 256:
C     sparse Hessians, chainp77.f)
      CALL VCINEW(PWMOD, N, M, NG, 512, H, RPAR, IPAR, IH, ISTAT)
      CALL CHECKI('VCINEW with IOPT = 512', ISTAT, 1, NBAD)
C     unknown scheme, stages out of range (the model stays usable)
      CALL VCINEW(PWMOD, N, M, NG, 8, H, RPAR, IPAR, IH, ISTAT)
      CALL CHECKI('VCINEW', ISTAT, 0, NBAD)
      CALL VCISCH(IH, 7, 1, ISTAT)
      CALL CHECKI('VCISCH unknown scheme', ISTAT, 1, NBAD)
      CALL VCIMSG(IH, MSG)
      WRITE (*, '(2A)') ' unknown scheme: ', MSG(1:80)
      CALL CHECKS('unknown scheme message', MSG, 'unknown scheme',
     &            NBAD)
      CALL VCISCH(IH, 3, 0, ISTAT)
      CALL CHECKI('VCISCH lobatto s = 0', ISTAT, 1, NBAD)
      CALL VCISCH(IH, 3, 9, ISTAT)
      CALL CHECKI('VCISCH lobatto s = 9', ISTAT, 1, NBAD)
      CALL VCISCH(IH, 1, 0, ISTAT)
      CALL CHECKI('VCISCH left (stages ignored)', ISTAT, 0, NBAD)
      CALL VCIDEL(IH)
C     a TASK failing in mid-run (IPAR(1) = 2: TASK 11 gives IERR = -5
C     once Q > 0.5) stops the run with ISTAT = 2 naming it. (IPAR is
C     set before VCINEW: the compiler need not store into an array
C     that no later call of this program unit receives.)
      IPAR(1) = 2
      CALL VCINEW(PWMOD, N, M, NG, 8, H, RPAR, IPAR, IH, ISTAT)
      CALL CHECKI('VCINEW', ISTAT, 0, NBAD)
      CALL VCISCH(IH, 3, NSTG, ISTAT)
      CALL CHECKI('VCISCH lobatto', ISTAT, 0, NBAD)
      CALL VCIINM(IH, 0.0D0, Q0, P0, ISTAT)
      CALL CHECKI('VCIINM', ISTAT, 0, NBAD)
      CALL VCIADV(IH, 200, 1, T, Q, P, NIMP, TIMP, LTIMP, ISTAT)
      CALL CHECKI('failing TASK 11', ISTAT, 2, NBAD)
      CALL VCIMSG(IH, MSG)
      WRITE (*, '(2A)') ' failing TASK 11: ', MSG(1:160)
      CALL CHECKS('failing TASK 11 message', MSG, 'TASK = 11', NBAD)
      CALL VCIDEL(IH)
C     the safety net (issue 27, VCISPL, VCINET): midpoint at h = 0.8
C     (h omega = 2.5) with the poke screen off (VCIPOK(IH, 0), as
C     measured before the screen was on by default) meets an impact
C     whose blended root would move H by 11.8 at t = 0.8 (issue 27:
C     refused); off (MAXSPL = 1) the run stops there with ISTAT = 5,
C     on (default 16) it reaches t = 10.4 in 13 steps, some split in 2
C     or more parts (4 steps in 2 parts measured)
      IPAR(1) = 0
      DO 15 K = 1, 2
        CALL VCINEW(PWMOD, N, M, NG, 8, 0.8D0, RPAR, IPAR, IH, ISTAT)
        CALL CHECKI('VCINEW h = 0.8', ISTAT, 0, NBAD)
        CALL VCISCH(IH, 2, 1, ISTAT)
        CALL CHECKI('VCISCH midpoint', ISTAT, 0, NBAD)
        CALL VCIPOK(IH, 2, ISTAT)
        CALL CHECKI('VCIPOK ION = 2', ISTAT, 1, NBAD)
        CALL VCIPOK(IH, 0, ISTAT)
        CALL CHECKI('VCIPOK off', ISTAT, 0, NBAD)
        IF (K .EQ. 1) CALL VCISPL(IH, 1, ISTAT)
        CALL CHECKI('VCISPL', ISTAT, 0, NBAD)
        CALL VCIINM(IH, 0.0D0, Q0, P0, ISTAT)
        CALL CHECKI('VCIINM', ISTAT, 0, NBAD)
        CALL VCIADV(IH, 13, 1, T, Q, P, NIMP, TIMP, LTIMP, ISTAT)
        CALL CHECKI('net off / on: status', ISTAT, 5 * (2 - K), NBAD)
        CALL VCINET(IH, NSPL, MOSTSP, IPASS)
        CALL CHECKI('VCINET', IPASS, 0, NBAD)
        WRITE (*, '(A,I2,A,F6.2,A,I3,A,I3)') ' net', K - 1, ': t =',
     &    T, ', steps split', NSPL, ', most parts', MOSTSP
        IF (K .EQ. 1) THEN
          CALL CHECKR('net off: stop at t = 0.8', T, 0.8D0, 1.0D-12,
     &                NBAD)
          CALL CHECKI('net off: nothing split', NSPL, 0, NBAD)
        ELSE
          CALL CHECKR('net on: t = 10.4', T, 10.4D0, 1.0D-12, NBAD)
          IF (NSPL .LT. 1 .OR. MOSTSP .LT. 2) THEN
            WRITE (*, '(A)') ' FAIL: net on: no step counted as split'
            NBAD = NBAD + 1
          END IF
        END IF
        CALL VCIDEL(IH)
   15 CONTINUE
C     the model checker (issue 31): the model passes; with a wrong
C     sign in dL/dq (IPAR(1) = 7) it fails and VCIMSG names dl_dq
      DO 20 K = 1, 2
        IPAR(1) = 0
        IF (K .EQ. 2) IPAR(1) = 7
        CALL VCINEW(PWMOD, N, M, NG, 15, H, RPAR, IPAR, IH, ISTAT)
        CALL CHECKI('VCINEW', ISTAT, 0, NBAD)
        Q(1) = 0.3D0
        P(1) = 1.7D0
        CALL VCICHK(IH, Q, P, H, 0.0D0, IPASS, WORST, ISTAT)
        CALL CHECKI('VCICHK', ISTAT, 0, NBAD)
        CALL CHECKI('VCICHK verdict', IPASS, 2 - K, NBAD)
        IF (K .EQ. 2) THEN
          CALL VCIMSG(IH, MSG)
          WRITE (*, '(2A)') ' wrong dL/dq: ', MSG(1:100)
          CALL CHECKS('VCICHK message', MSG, 'dl_dq', NBAD)
        END IF
        CALL VCIDEL(IH)
   20 CONTINUE
      IPAR(1) = 0
C     a scheme for a discrete model (IOPT without bit 8)
      CALL VCINEW(PWMOD, N, M, NG, 2, H, RPAR, IPAR, IH, ISTAT)
      CALL CHECKI('VCINEW discrete', ISTAT, 0, NBAD)
      CALL VCISCH(IH, 3, NSTG, ISTAT)
      CALL CHECKI('VCISCH on a discrete model', ISTAT, 1, NBAD)
      CALL VCIDEL(IH)
      CALL VCISCH(IH, 3, NSTG, ISTAT)
      CALL CHECKI('VCISCH on a deleted handle', ISTAT, 1, NBAD)
C
C     3. Restart (VCIOUT, VCIRST, VCICLS): 200 steps in one run; then
C        83 steps into a file, and a new integrator restarted from it
C        (VCIRST) appending the other 117 (VCIOUT, IAPP = 1): the same
C        final state to the last bit (tolerance 0)
      IPAR(1) = 0
      CALL VCINEW(PWMOD, N, M, NG, 15, H, RPAR, IPAR, IH, ISTAT)
      CALL VCISCH(IH, 3, NSTG, ISTAT)
      CALL VCITOL(IH, 0.0D0, 1.0D-15, 30, ISTAT)
      CALL VCIINM(IH, 0.0D0, Q0, P0, ISTAT)
      CALL VCIADV(IH, 200, 1, T1, Q1, P1, NIMP, TIMP, LTIMP, ISTAT)
      CALL CHECKI('whole run', ISTAT, 0, NBAD)
      CALL VCIDEL(IH)
      DO 30 K = 1, 2
        CALL VCINEW(PWMOD, N, M, NG, 15, H, RPAR, IPAR, IH, ISTAT)
        CALL VCISCH(IH, 3, NSTG, ISTAT)
        CALL VCITOL(IH, 0.0D0, 1.0D-15, 30, ISTAT)
        IF (K .EQ. 1) THEN
          CALL VCIINM(IH, 0.0D0, Q0, P0, ISTAT)
          CALL VCIOUT(IH, 'pendw77_restart.h5', 0, ISTAT)
          IF (ISTAT .EQ. 8) THEN
C           a build without HDF5 says so; nothing to restart from
            CALL VCIMSG(IH, MSG)
            CALL CHECKS('VCIOUT without HDF5', MSG,
     &                  'built without HDF5', NBAD)
            CALL VCIDEL(IH)
            GO TO 40
          END IF
          CALL CHECKI('VCIOUT', ISTAT, 0, NBAD)
          CALL VCIADV(IH, 83, 1, T, Q, P, NIMP, TIMP, LTIMP, ISTAT)
          CALL CHECKI('first part', ISTAT, 0, NBAD)
C         one file, one run: no new start while it holds steps
          CALL VCIINM(IH, 0.0D0, Q0, P0, ISTAT)
          CALL CHECKI('VCIINM with the file open', ISTAT, 9, NBAD)
        ELSE
          CALL VCIRST(IH, 'pendw77_restart.h5', ISTAT)
          CALL CHECKI('VCIRST', ISTAT, 0, NBAD)
          CALL VCIOUT(IH, 'pendw77_restart.h5', 1, ISTAT)
          CALL CHECKI('VCIOUT append', ISTAT, 0, NBAD)
          CALL VCIADV(IH, 117, 1, T, Q, P, NIMP, TIMP, LTIMP, ISTAT)
          CALL CHECKI('second part', ISTAT, 0, NBAD)
          CALL CHECKI('impacts in the second part', MIN(NIMP, 1), 1,
     &                NBAD)
          CALL CHECKR('restart: same t', T, T1, 0.0D0, NBAD)
          CALL CHECKR('restart: same q', Q(1), Q1(1), 0.0D0, NBAD)
          CALL CHECKR('restart: same p', P(1), P1(1), 0.0D0, NBAD)
        END IF
        CALL VCICLS(IH, ISTAT)
        CALL CHECKI('VCICLS', ISTAT, 0, NBAD)
        CALL VCIDEL(IH)
   30 CONTINUE
C     the appended file restarts at its new end; refusals
      CALL VCINEW(PWMOD, N, M, NG, 15, H, RPAR, IPAR, IH, ISTAT)
      CALL VCISCH(IH, 3, NSTG, ISTAT)
      CALL VCIRST(IH, 'pendw77_restart.h5', ISTAT)
      CALL CHECKI('VCIRST appended file', ISTAT, 0, NBAD)
      CALL VCIADV(IH, 0, 1, T, Q, P, NIMP, TIMP, LTIMP, ISTAT)
      CALL CHECKR('appended file ends at the end', Q(1), Q1(1), 0.0D0,
     &            NBAD)
      CALL VCIRST(IH, 'pendw77_missing.h5', ISTAT)
      CALL CHECKI('VCIRST missing file', ISTAT, 8, NBAD)
      CALL VCIADV(IH, 1, 1, T, Q, P, NIMP, TIMP, LTIMP, ISTAT)
      CALL CHECKI('VCIADV after a failed VCIRST', ISTAT, 9, NBAD)
      CALL VCIOUT(IH, 'pendw77_restart.h5', 2, ISTAT)
      CALL CHECKI('VCIOUT IAPP = 2', ISTAT, 1, NBAD)
      CALL VCIDEL(IH)
      CALL VCINEW(PWMOD, N, M, NG, 15, 4.0D-2, RPAR, IPAR, IH, ISTAT)
      CALL VCIRST(IH, 'pendw77_restart.h5', ISTAT)
      CALL CHECKI('VCIRST with another H', ISTAT, 1, NBAD)
      CALL VCIMSG(IH, MSG)
      WRITE (*, '(2A)') ' another H: ', MSG(1:160)
      CALL CHECKS('another H message', MSG, 'step length', NBAD)
      CALL VCIDEL(IH)
C
C     4. The file of a run that failed says so (legacy_output_status
C        reads it): TASK 11 fails in mid-run (IPAR(1) = 2), then a call
C        that succeeds (VCIMSG), then VCICLS: status 2 and the message
C        in pendw77_failed.h5
      IPAR(1) = 2
      CALL VCINEW(PWMOD, N, M, NG, 8, H, RPAR, IPAR, IH, ISTAT)
      CALL VCISCH(IH, 3, NSTG, ISTAT)
      CALL VCIINM(IH, 0.0D0, Q0, P0, ISTAT)
      CALL VCIOUT(IH, 'pendw77_failed.h5', 0, ISTAT)
      CALL CHECKI('VCIOUT (failing run)', ISTAT, 0, NBAD)
      CALL VCIADV(IH, 200, 1, T, Q, P, NIMP, TIMP, LTIMP, ISTAT)
      CALL CHECKI('failing run into a file', ISTAT, 2, NBAD)
      CALL VCIMSG(IH, MSG)
      CALL VCICLS(IH, ISTAT)
      CALL CHECKI('VCICLS (failing run)', ISTAT, 0, NBAD)
      CALL VCIDEL(IH)
      IPAR(1) = 0
   40 CONTINUE
C
      IF (NBAD .NE. 0) THEN
        WRITE (*, '(A, I3, A)') ' legacy pendulum:', NBAD, ' FAILED'
        STOP 1
      END IF
      WRITE (*, '(A)') ' legacy pendulum: all checks passed'
      STOP
  900 WRITE (*, '(A)') ' FAIL: cannot read pendw77_ref.txt'
      STOP 1
      END
C
C     The walled pendulum as a continuous L(Q, V), V = dQ/dt. RPAR =
C     (gravity, wall angle). IPAR(1) = 2: TASK 11 fails (IERR = -5)
C     once Q has passed 0.5; 3: TASK 12 is not provided; 5: TASKs 13
C     and 9 are not provided; 7: dL/dq has the wrong sign; 9: it
C     overwrites its inputs after answering. IERR = -999 answers "not
C     provided".
      SUBROUTINE PWMOD(TASK, N, M, NG, Q, V, H, OUT, RPAR, IPAR, IERR)
      IMPLICIT NONE
      INTEGER TASK, N, M, NG, IPAR(*), IERR
      DOUBLE PRECISION Q(N), V(N), H, OUT(*), RPAR(*)
      DOUBLE PRECISION G, TW
      G = RPAR(1)
      TW = RPAR(2)
      IF (TASK .EQ. 10) THEN
        OUT(1) = 0.5D0 * V(1)**2 + G * COS(Q(1))
      ELSE IF (TASK .EQ. 11) THEN
        IF (IPAR(1) .EQ. 2 .AND. Q(1) .GT. 0.5D0) THEN
          IERR = -5
          RETURN
        END IF
        OUT(1) = -G * SIN(Q(1))
        IF (IPAR(1) .EQ. 7) OUT(1) = -OUT(1)
      ELSE IF (TASK .EQ. 12) THEN
        IF (IPAR(1) .EQ. 3) THEN
          IERR = -999
          RETURN
        END IF
        OUT(1) = V(1)
      ELSE IF (TASK .EQ. 13) THEN
        IF (IPAR(1) .EQ. 5) THEN
          IERR = -999
          RETURN
        END IF
C       d2L/dq2, d2L/dq dv, d2L/dv2 (each 1 x 1)
        OUT(1) = -G * COS(Q(1))
        OUT(2) = 0.0D0
        OUT(3) = 1.0D0
      ELSE IF (TASK .EQ. 7) THEN
        OUT(1) = TW - Q(1)
        OUT(2) = Q(1) + TW
      ELSE IF (TASK .EQ. 8) THEN
        OUT(1) = -1.0D0
        OUT(2) = 1.0D0
      ELSE IF (TASK .EQ. 9) THEN
        IF (IPAR(1) .EQ. 5) THEN
          IERR = -999
          RETURN
        END IF
C       H(Q, P) with P passed in V
        OUT(1) = 0.5D0 * V(1)**2 - G * COS(Q(1))
      ELSE
        IERR = -999
      END IF
      IF (IPAR(1) .EQ. 9) CALL PWBAD(TASK, N, M, NG, Q, V, H)
      END
C
C     What a careless routine might do to its inputs (IPAR(1) = 9):
C     H (passed as 0 for a continuous L) and N doubled, M, NG, TASK,
C     Q and V overwritten (N last: Q and V are dimensioned by it).
      SUBROUTINE PWBAD(TASK, N, M, NG, Q, V, H)
      IMPLICIT NONE
      INTEGER TASK, N, M, NG, I
      DOUBLE PRECISION Q(N), V(N), H
      DO 10 I = 1, N
        Q(I) = 1.0D300
        V(I) = -3.0D0
   10 CONTINUE
      H = 2.0D0 * H + 1.0D0
      TASK = 12
      M = -1
      NG = 100000
      N = 2 * N + 1000
      END
