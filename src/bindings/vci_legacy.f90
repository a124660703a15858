!> The legacy Fortran entry point: external subroutines (no module needed by the caller) that a
!> fixed-form Fortran 77 program calls with one EXTERNAL model routine, explicit-shape arrays,
!> RPAR/IPAR user arrays and an integer status, in the manner of ODEPACK's and DASSL's drivers.
!> See docs/C_API.md ("Legacy Fortran") for the calling sequence in full.
!>
!>     CALL VCIRUN(MODEL, N, M, NG, IOPT, H, T0, Q0, Q1, NSTEPS,
!>    &            T, Q, P, NIMP, TIMP, LTIMP, RPAR, IPAR, ISTAT, MSG)
!>
!> integrates NSTEPS steps forward from the initial pair (Q0 at T0, Q1 at T0 + H) and returns the
!> final state and the impact times. For runs in pieces, backward runs or other tolerances there
!> is an integer-handle interface over the same integrator:
!>
!>     VCINEW(MODEL, N, M, NG, IOPT, H, RPAR, IPAR, IH, ISTAT)   create; IH > 0 names it
!>     VCISCH(IH, ISCH, NSTG, ISTAT)                             scheme of a continuous model
!>     VCITOL(IH, ATOL, RTOL, MAXIT, ISTAT)                      Newton tolerances
!>     VCIENG(IH, MODE, ISTAT)                                   impact energy: 0 discrete, 1 hamiltonian
!>     VCIINP(IH, T0, Q0, Q1, ISTAT)                             start from a pair
!>     VCIINM(IH, T0, Q0, P0, ISTAT)                             start from (q, p)
!>     VCIADV(IH, NSTEPS, IDIR, T, Q, P, NIMP, TIMP, LTIMP, ISTAT) advance; state and impacts out
!>     VCIMSG(IH, MSG)                                           message of the last call
!>     VCIDEL(IH)                                                free; IH becomes 0
!>     VCICHK(IH, Q, V, H, TOL, IPASS, WORST, ISTAT)              model checker (vci_model_check)
!>     VCIOUT(IH, PATH, IAPP, ISTAT)                             HDF5 output of later steps (IAPP 1: append)
!>     VCICLS(IH, ISTAT)                                         finish the output file
!>     VCIRST(IH, PATH, ISTAT)                                   restart from an HDF5 file's last state
!>     VCIBND(IH, IBW, ICHK, ISTAT)                              Hessians banded with half-bandwidth IBW
!>     VCIPAT(IH, NNZ, ICOLP, IROW, ICHK, ISTAT)                 Hessians sparse: a pattern (issue 28)
!>
!> VCIPAT declares the N x N pattern of the Hessian blocks (the TASK 4 / TASK 13 matrices) in
!> compressed columns, 1-based: column J's nonzero rows are IROW(ICOLP(J) : ICOLP(J+1) - 1),
!> strictly increasing; ICOLP(1) = 1, ICOLP does not decrease, ICOLP(N+1) = NNZ + 1. The library
!> closes it under transposition and adds the diagonal. NNZ < 0 withdraws it (dense again). It
!> needs a library built with the sparse solver (CMake VCI_SPARSE, SuiteSparse KLU): without it
!> ISTAT = 1 and VCIMSG says so. Like VCIBND, call it before VCIINP / VCIINM.
!>
!> The model routine (one EXTERNAL, selecting what to compute by TASK as MINPACK's FCN does
!> with IFLAG):
!>
!>     SUBROUTINE MODEL(TASK, N, M, NG, Q, V, H, OUT, RPAR, IPAR, IERR)
!>     INTEGER TASK, N, M, NG, IPAR(*), IERR
!>     DOUBLE PRECISION Q(N), V(N), H, OUT(*), RPAR(*)
!>
!> A discrete Lagrangian L_d(Q, V, H) (IOPT without bit 8):
!>
!>     TASK 1: OUT(1:N)    = D1 L_d(Q, V, H)          2: OUT(1:N) = D2 L_d(Q, V, H)
!>     TASK 3: OUT(1)      = D3 L_d(Q, V, H)
!>     TASK 4: OUT(1:N*N)  = d2 L_d/dQ_i dV_j at (Q, V, H), column-major        (IOPT bit 1)
!>     TASK 6: OUT(1:M)    = omega_d(Q, V, H) with Q the base, V the other point (M > 0)
!>     TASK 19: OUT(1:2*N+1+N*N) = D1 L_d, D2 L_d, D3 L_d and the TASK 4 matrix, one after the
!>              other, in one call (shared sines and cosines computed once; it replaces TASKs 1-4
!>              in the solves)                                               (IOPT bit 128)
!>
!> A continuous Lagrangian L(Q, V), V the velocity (IOPT bit 8; the library discretises it by the
!> scheme VCISCH chooses, midpoint by default; H is passed as 0):
!>
!>     TASK 10: OUT(1)       = L(Q, V)
!>     TASK 11: OUT(1:N)     = dL/dQ(Q, V)            12: OUT(1:N) = dL/dV(Q, V)
!>     TASK 13: OUT(1:3*N*N) = the blocks d2L/dQ dQ, d2L/dQ dV, d2L/dV dV, each N x N column-major
!>              (block (i, j) = d2L/dx_i dy_j), one after the other                (IOPT bit 1)
!>     TASK 18: OUT(1:3*(2*IBW+1)*N) = the same blocks on the band |i - j| <= IBW that VCIBND
!>              declared, each in LAPACK band storage ((2*IBW+1) x N column-major, entry (i, j)
!>              in row IBW+1+i-j of column j), one after the other                (IOPT bit 64)
!>     TASK 20: OUT(1:3*NNZ) = the same blocks in the pattern VCIPAT declared, each NNZ values in
!>              IROW's order (entry (IROW(k), J) for ICOLP(J) <= k < ICOLP(J+1)), one after the
!>              other; entries the library adds (transposes, diagonal) not declared are zero
!>                                                                                (IOPT bit 256)
!>
!> A separable L = ½ Vᵀ M V − V(Q) with a constant M (IOPT bit 16; every scheme of a continuous
!> model, and the explicit compositions VCISCH(IH, 4, ORDER, ...); M must be 0, H is derived):
!>
!>     TASK 14: OUT(1)       = the potential V(Q)     15: OUT(1:N) = its gradient at Q
!>     TASK 16: OUT(1:N*N)   = its Hessian at Q, column-major                    (IOPT bit 1)
!>     TASK 17: OUT(1:N)     = the diagonal of M, or with IOPT bit 32 OUT(1:N*N) = M (column-major,
!>              symmetric positive definite); called once, at VCINEW
!>     (NG > 0 needs TASK 8, IOPT bit 2: the explicit impact uses the gap gradients)
!>
!> All kinds:
!>
!>     TASK 5: OUT(1:N*M)  = one-forms Omega(Q), column mu = omega^mu            (M > 0)
!>     TASK 7: OUT(1:NG)   = gap functions g(Q)                                  (NG > 0)
!>     TASK 8: OUT(1:N*NG) = gap gradients at Q, column j = grad g_j            (IOPT bit 2)
!>     TASK 9: OUT(1)      = energy H(Q, P) with P passed in V                   (IOPT bit 4)
!>
!> IERR arrives 0; the callback contract of the C interface holds: IERR > 0 is a recoverable
!> failure (at a trial point of Newton's line search the solver backs off, elsewhere the step
!> stops with ISTAT = 2), IERR < 0 an unrecoverable one (the step stops at once, ISTAT = 2). The
!> message then names the TASK and the IERR. IERR = -999 (IERR_NOT_PROVIDED, and only that value)
!> answers "this TASK is not provided": on the library's probe of an optional TASK it does without
!> it (differences it, or uses the Legendre inversion for H), on a required TASK VCINEW fails with
!> ISTAT = 1 naming it, and anywhere else it is an unrecoverable failure. IOPT declares the optional
!> tasks the routine supplies (sum of 1: Hessian(s), 2: gap gradients, 4: energy, 64: TASK 18,
!> 128: TASK 19) and the kind of model (8: continuous, 16: separable, 32: its dense M); the routine is never called for an optional task IOPT leaves out. ISTAT
!> takes the values of the C enum (0 ok, 1 argument, 2 callback, 3 non-finite, 4 Newton, 5 impact,
!> 6 too many impacts, 7 inadmissible, 8 I/O, 9 call out of order).
module vci_legacy
  use, intrinsic :: iso_c_binding, only: c_ptr, c_f_pointer, c_null_ptr
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use vci_kinds, only: dp, i8
  use vci_status
  use vci_model_base, only: vci_model_base_t
  use vci_model, only: vci_model_t
  use vci_lagrangian, only: vci_lagrangian_t
  use vci_separable, only: vci_separable_t
  use vci_observer, only: vci_observer_t, vci_impact_t, vci_run_info_t
  use vci_integrator, only: vci_integrator_t
  use vci_callback_adapter, only: vci_callback_record_t
  use vci_limits, only: vci_size_problem
  use vci_model_check, only: vci_check_model, vci_check_report_t
  use vci_checkpoint, only: vci_checkpoint_t
  use vci_bindings_h5, only: bindings_open_h5, bindings_read_h5
  use vci_sparse, only: sparse_available, pattern_arrays_error
  implicit none
  private

  public :: vci_legacy_model_fn, legacy_new, legacy_get, legacy_after, legacy_delete, legacy_advance, legacy_message
  public :: legacy_set_scheme, legacy_init, legacy_check, legacy_size
  public :: legacy_open_output, legacy_close_output, legacy_restore, legacy_bandwidth
  public :: legacy_pattern

  !> TASK codes of the model routine: a discrete L_d (1-4, 6), a continuous L (10-13), both (5, 7-9).
  integer, parameter, public :: TASK_D1 = 1, TASK_D2 = 2, TASK_D3 = 3, TASK_HESSIAN = 4, TASK_FORMS = 5, &
                                TASK_DCONSTRAINT = 6, TASK_GAPS = 7, TASK_GAP_GRADS = 8, TASK_ENERGY = 9, &
                                TASK_LAGRANGIAN = 10, TASK_DL_DQ = 11, TASK_DL_DV = 12, TASK_L_HESSIANS = 13, &
                                TASK_POTENTIAL = 14, TASK_POTENTIAL_GRAD = 15, TASK_POTENTIAL_HESSIAN = 16, &
                                TASK_MASS = 17, TASK_L_HESSIANS_BAND = 18, TASK_LD_FUSED = 19, &
                                TASK_L_HESSIANS_SPARSE = 20
  !> IOPT bits: which optional tasks the model routine supplies, and whether it is a continuous L.
  integer, parameter, public :: IOPT_HESSIAN = 1, IOPT_GAP_GRADS = 2, IOPT_ENERGY = 4, IOPT_CONTINUOUS = 8, &
                                IOPT_SEPARABLE = 16, IOPT_DENSE_MASS = 32, IOPT_BAND_HESSIANS = 64, &
                                IOPT_LD_FUSED = 128, IOPT_SPARSE_HESSIANS = 256
  !> IERR with which the model routine answers "this TASK is not provided" (no other value means it).
  integer, parameter, public :: IERR_NOT_PROVIDED = -999

  !> The model routine's interface as the library sees it (the caller needs no interface).
  abstract interface
    subroutine vci_legacy_model_fn(task, n, m, ng, q, v, h, out, rpar, ipar, ierr)
      import :: dp
      integer, intent(in) :: task, n, m, ng
      real(dp), intent(in) :: q(n), v(n), h
      real(dp), intent(inout) :: out(*)
      real(dp), intent(inout) :: rpar(*)
      integer, intent(inout) :: ipar(*)
      integer, intent(inout) :: ierr
    end subroutine vci_legacy_model_fn
  end interface

  !> The caller's EXTERNAL routine with its RPAR/IPAR (which must outlive it), its IOPT, and the
  !> record of its last failing TASK: the one TASK dispatch of both kinds of legacy model.
  type :: legacy_routine_t
    procedure(vci_legacy_model_fn), pointer, nopass :: fn => null()
    integer :: iopt = 0
    type(c_ptr) :: rpar = c_null_ptr, ipar = c_null_ptr
    type(vci_callback_record_t) :: record     !< the last failing TASK and its IERR
    !> What the routine receives for Q and V (sized N at VCINEW): copies, so that a routine that
    !> writes its inputs changes nothing of the library's (see call_task)
    real(dp), allocatable :: q(:), v(:)
  end type legacy_routine_t

  !> A discrete model (L_d) made of the routine.
  type, extends(vci_model_t) :: legacy_model_t
    type(legacy_routine_t) :: routine
    real(dp), allocatable :: fwork(:)   !< OUT of TASK 19 (2 n + 1 + n^2), when IOPT has bit 128
  contains
    procedure :: d1 => lm_d1
    procedure :: d2 => lm_d2
    procedure :: d3 => lm_d3
    procedure :: mixed_hessian => lm_hessian
    procedure :: ld_fused => lm_ld_fused
    procedure :: constraint_forms => lm_forms
    procedure :: discrete_constraint => lm_dconstraint
    procedure :: gaps => lm_gaps
    procedure :: gap_gradients => lm_gap_grads
    procedure :: energy => lm_energy
  end type legacy_model_t

  !> A continuous model (L) made of the routine (IOPT bit 8).
  type, extends(vci_lagrangian_t) :: legacy_lagrangian_t
    type(legacy_routine_t) :: routine
    real(dp), allocatable :: hwork(:)   !< OUT of TASK 13 (3 n^2), when IOPT has bit 1
    real(dp), allocatable :: bwork(:)   !< OUT of TASK 18 (3 (2 bw + 1) n), when IOPT has bit 64
    real(dp), allocatable :: swork(:)   !< OUT of TASK 20 (3 nnz), when IOPT has bit 256
  contains
    procedure :: lagrangian => ll_value
    procedure :: dl_dq => ll_dl_dq
    procedure :: dl_dv => ll_dl_dv
    procedure :: hessians => ll_hessians
    procedure :: hessians_band => ll_hessians_band
    procedure :: hessians_sparse => ll_hessians_sparse
    procedure :: constraint_forms => ll_forms
    procedure :: gaps => ll_gaps
    procedure :: gap_gradients => ll_gap_grads
    procedure :: energy => ll_energy
  end type legacy_lagrangian_t

  !> A separable model (L = ½ vᵀ M v − V, M constant) made of the routine (IOPT bit 16).
  type, extends(vci_separable_t) :: legacy_separable_t
    type(legacy_routine_t) :: routine
  contains
    procedure :: potential => ls_potential
    procedure :: potential_gradient => ls_gradient
    procedure :: potential_hessian => ls_hessian
    procedure :: gaps => ls_gaps
    procedure :: gap_gradients => ls_gap_grads
  end type legacy_separable_t

  !> The output file of one integrator of the handle interface (VCIOUT): one run from VCIOUT to
  !> VCICLS or VCIDEL, however many VCIADV calls it spans (all one way, from one start).
  type :: legacy_output_t
    class(vci_observer_t), allocatable :: writer
    logical :: started = .false.
    integer :: direction = 0        !< of the file's run, once started
    !> the run's end the file records: the last VCIADV's status and message (not those of the
    !> VCICLS or VCIDEL that writes them, nor of a call between)
    integer :: run_status = 0
    character(len=VCI_MSG_LEN) :: run_message = ''
  end type legacy_output_t

  !> Records the impact times of one VCIADV call; clears the callback record after every step;
  !> hands everything on to the output file, if any.
  type, extends(vci_observer_t) :: impact_log_t
    integer :: count = 0
    real(dp), allocatable :: times(:)
    type(vci_callback_record_t), pointer :: record => null()
    type(legacy_output_t), pointer :: out => null()
  contains
    procedure :: on_impact => log_impact
    procedure :: on_step => log_step
    procedure :: on_start => log_start
    procedure :: keeps_checkpoints => log_keeps_checkpoints
    procedure :: wants_checkpoint => log_wants_checkpoint
    procedure :: on_checkpoint => log_checkpoint
    procedure :: failure_cause => log_failure_cause
  end type impact_log_t

  !> One live integrator of the handle interface, over one of the two kinds of model.
  type :: slot_t
    integer :: id = 0
    type(legacy_model_t), pointer :: model => null()
    type(legacy_lagrangian_t), pointer :: lag => null()
    type(legacy_separable_t), pointer :: sep => null()
    type(vci_integrator_t), pointer :: integ => null()
    type(legacy_output_t), pointer :: out => null()   !< VCIOUT's file, if open
  end type slot_t

  type(slot_t), allocatable, save :: slots(:)
  integer, save :: last_id = 0     !< handles are never reused, so a deleted one is always detected
  !> Message of the last failure without a live handle to hold it (VCINEW, bad IH): VCIMSG(0, MSG).
  character(len=VCI_MSG_LEN), save :: global_message = ''

contains

  !> Call the model routine for one task (nout outputs) of a model with sizes n, m, ng; IERR goes
  !> through the callback adapter. declined: the routine answered IERR_NOT_PROVIDED (the caller
  !> marks its model; stat keeps the code, a failure wherever the answer was not a probe's).
  subroutine call_task(r, n, m, ng, task, q, v, h, out, nout, stat, declined)
    type(legacy_routine_t), intent(inout) :: r
    integer, intent(in) :: n, m, ng, task, nout
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(inout) :: out(*)
    integer, intent(inout) :: stat
    logical, intent(out) :: declined
    real(dp), pointer, contiguous :: rp(:)
    integer, pointer, contiguous :: ip(:)
    integer :: ierr, task_c, n_c, m_c, ng_c
    real(dp) :: h_c
    character(len=48) :: name
    call c_f_pointer(r%rpar, rp, [1])
    call c_f_pointer(r%ipar, ip, [1])
    ierr = 0
    out(1:nout) = 0.0_dp   ! defined even where a failing routine left it unwritten
    ! A Fortran 77 routine gets every argument by reference and may write any of them: it gets
    ! copies of what it must not change (TASK, N, M, NG, Q, V, H), never the library's own
    ! variables (the model's N, the scheme's H, a Newton iterate) or a constant
    task_c = task; n_c = n; m_c = m; ng_c = ng; h_c = h
    r%q(1:n) = q(1:n); r%v(1:n) = v(1:n)
    call r%fn(task_c, n_c, m_c, ng_c, r%q, r%v, h_c, out(1), rp, ip, ierr)   ! out(1): sequence association
    declined = ierr == IERR_NOT_PROVIDED
    if (declined) then
      write (name, '(a,i0,a)') 'MODEL with TASK = ', task, ' (not provided)'
    else
      write (name, '(a,i0)') 'MODEL with TASK = ', task
    end if
    call r%record%note(ierr, trim(name), all(ieee_is_finite(out(1:nout))), stat)
  end subroutine call_task

  !> The model's answer "not provided" (its mark), keeping the failure code in stat.
  subroutine decline(model, stat)
    class(vci_model_base_t), intent(inout) :: model
    integer, intent(inout) :: stat
    integer :: code
    code = stat
    call model%not_provided(stat)
    stat = code
  end subroutine decline

  ! ---------------------------------------------------------------------------------------------
  ! the discrete model: L_d's tasks

  !> One task of the discrete model, with the not-provided answer marked on it.
  subroutine lm_task(self, task, q, v, h, out, nout, stat)
    class(legacy_model_t), intent(inout) :: self
    integer, intent(in) :: task, nout
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(inout) :: out(*)
    integer, intent(inout) :: stat
    logical :: declined
    call call_task(self%routine, self%n, self%m, self%n_gaps, task, q, v, h, out, nout, stat, declined)
    if (declined) call decline(self, stat)
  end subroutine lm_task

  subroutine lm_d1(self, q, v, h, out, stat)
    class(legacy_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    call lm_task(self, TASK_D1, q, v, h, out, size(out), stat)
  end subroutine lm_d1

  subroutine lm_d2(self, q, v, h, out, stat)
    class(legacy_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    call lm_task(self, TASK_D2, q, v, h, out, size(out), stat)
  end subroutine lm_d2

  subroutine lm_d3(self, q, v, h, out, stat)
    class(legacy_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out
    integer, intent(inout) :: stat
    real(dp) :: tmp(1)
    tmp = 0.0_dp
    call lm_task(self, TASK_D3, q, v, h, tmp, 1, stat)
    out = tmp(1)
  end subroutine lm_d3

  subroutine lm_hessian(self, q, v, h, hess, stat)
    class(legacy_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: hess(:, :)
    integer, intent(inout) :: stat
    if (iand(self%routine%iopt, IOPT_HESSIAN) == 0) then
      hess = 0.0_dp; call self%not_provided(stat); return
    end if
    call lm_task(self, TASK_HESSIAN, q, v, h, hess, size(hess), stat)
  end subroutine lm_hessian

  !> TASK 19: D1, D2, D3 and the mixed Hessian in one call, unpacked from OUT.
  subroutine lm_ld_fused(self, q, v, h, d1, d2, d3, hess, stat)
    class(legacy_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: d1(:), d2(:), d3, hess(:, :)
    integer, intent(inout) :: stat
    integer :: n, i, j
    n = self%n
    d1 = 0.0_dp; d2 = 0.0_dp; d3 = 0.0_dp; hess = 0.0_dp
    if (iand(self%routine%iopt, IOPT_LD_FUSED) == 0 .or. .not. allocated(self%fwork)) then
      call self%not_provided(stat); return
    end if
    call lm_task(self, TASK_LD_FUSED, q, v, h, self%fwork, size(self%fwork), stat)
    do i = 1, n
      d1(i) = self%fwork(i); d2(i) = self%fwork(n + i)
    end do
    d3 = self%fwork(2 * n + 1)
    do j = 1, n
      do i = 1, n
        hess(i, j) = self%fwork(2 * n + 1 + i + n * (j - 1))
      end do
    end do
  end subroutine lm_ld_fused

  subroutine lm_forms(self, q, omega, stat)
    class(legacy_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: omega(:, :)
    integer, intent(inout) :: stat
    call lm_task(self, TASK_FORMS, q, q, 0.0_dp, omega, size(omega), stat)
  end subroutine lm_forms

  subroutine lm_dconstraint(self, base, other, h, out, stat)
    class(legacy_model_t), intent(inout) :: self
    real(dp), intent(in) :: base(:), other(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    call lm_task(self, TASK_DCONSTRAINT, base, other, h, out, size(out), stat)
  end subroutine lm_dconstraint

  subroutine lm_gaps(self, q, g, stat)
    class(legacy_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    call lm_task(self, TASK_GAPS, q, q, 0.0_dp, g, size(g), stat)
  end subroutine lm_gaps

  subroutine lm_gap_grads(self, q, dg, stat)
    class(legacy_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    if (iand(self%routine%iopt, IOPT_GAP_GRADS) == 0) then
      dg = 0.0_dp; call self%not_provided(stat); return
    end if
    call lm_task(self, TASK_GAP_GRADS, q, q, 0.0_dp, dg, size(dg), stat)
  end subroutine lm_gap_grads

  subroutine lm_energy(self, q, p, e, stat)
    class(legacy_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    real(dp) :: tmp(1)
    if (iand(self%routine%iopt, IOPT_ENERGY) == 0) then
      e = 0.0_dp; call self%not_provided(stat); return
    end if
    tmp = 0.0_dp
    call lm_task(self, TASK_ENERGY, q, p, 0.0_dp, tmp, 1, stat)
    e = tmp(1)
  end subroutine lm_energy

  ! ---------------------------------------------------------------------------------------------
  ! the continuous model: L's tasks, through the same dispatch and record (H is passed as 0)

  !> One task of the continuous model, with the not-provided answer marked on it.
  subroutine ll_task(self, task, q, v, out, nout, stat)
    class(legacy_lagrangian_t), intent(inout) :: self
    integer, intent(in) :: task, nout
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(inout) :: out(*)
    integer, intent(inout) :: stat
    logical :: declined
    call call_task(self%routine, self%n, self%m, self%n_gaps, task, q, v, 0.0_dp, out, nout, stat, declined)
    if (declined) call decline(self, stat)
  end subroutine ll_task

  subroutine ll_value(self, q, v, l, stat)
    class(legacy_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: l
    integer, intent(inout) :: stat
    real(dp) :: tmp(1)
    tmp = 0.0_dp
    call ll_task(self, TASK_LAGRANGIAN, q, v, tmp, 1, stat)
    l = tmp(1)
  end subroutine ll_value

  subroutine ll_dl_dq(self, q, v, out, stat)
    class(legacy_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    call ll_task(self, TASK_DL_DQ, q, v, out, size(out), stat)
  end subroutine ll_dl_dq

  subroutine ll_dl_dv(self, q, v, out, stat)
    class(legacy_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    call ll_task(self, TASK_DL_DV, q, v, out, size(out), stat)
  end subroutine ll_dl_dv

  !> The three blocks come back one after the other in one OUT(1:3*N*N) (hwork, sized at VCINEW).
  subroutine ll_hessians(self, q, v, lqq, lqv, lvv, stat)
    class(legacy_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: lqq(:, :), lqv(:, :), lvv(:, :)
    integer, intent(inout) :: stat
    integer :: nn
    logical :: declined
    lqq = 0.0_dp; lqv = 0.0_dp; lvv = 0.0_dp
    if (iand(self%routine%iopt, IOPT_HESSIAN) == 0) then
      call self%not_provided(stat); return
    end if
    nn = self%n * self%n
    call call_task(self%routine, self%n, self%m, self%n_gaps, TASK_L_HESSIANS, q, v, 0.0_dp, self%hwork, 3 * nn, &
                   stat, declined)
    if (declined) call decline(self, stat)
    lqq = reshape(self%hwork(1:nn), [self%n, self%n])
    lqv = reshape(self%hwork(nn + 1:2 * nn), [self%n, self%n])
    lvv = reshape(self%hwork(2 * nn + 1:3 * nn), [self%n, self%n])
  end subroutine ll_hessians

  !> TASK 18: the three blocks in band storage one after the other in OUT(1:3*(2*bw+1)*N).
  subroutine ll_hessians_band(self, q, v, bw, lqq, lqv, lvv, stat)
    class(legacy_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    integer, intent(in) :: bw
    real(dp), intent(out) :: lqq(:, :), lqv(:, :), lvv(:, :)
    integer, intent(inout) :: stat
    integer :: nb, st
    logical :: declined
    lqq = 0.0_dp; lqv = 0.0_dp; lvv = 0.0_dp
    if (iand(self%routine%iopt, IOPT_BAND_HESSIANS) == 0 .or. bw < 0) then
      call self%not_provided(stat); return
    end if
    nb = (2 * bw + 1) * self%n
    if (allocated(self%bwork)) then
      if (size(self%bwork) /= 3 * nb) deallocate (self%bwork)
    end if
    if (.not. allocated(self%bwork)) then
      allocate (self%bwork(3 * nb), stat=st)
      if (st /= 0) then
        stat = -1; return        ! (unrecoverable: the step stops, naming hessians)
      end if
    end if
    call call_task(self%routine, self%n, self%m, self%n_gaps, TASK_L_HESSIANS_BAND, q, v, 0.0_dp, self%bwork, &
                   3 * nb, stat, declined)
    if (declined) call decline(self, stat)
    lqq = reshape(self%bwork(1:nb), [2 * bw + 1, self%n])
    lqv = reshape(self%bwork(nb + 1:2 * nb), [2 * bw + 1, self%n])
    lvv = reshape(self%bwork(2 * nb + 1:3 * nb), [2 * bw + 1, self%n])
  end subroutine ll_hessians_band

  !> TASK 20: the three blocks in the declared pattern's order, one after the other in OUT(1:3*NNZ).
  subroutine ll_hessians_sparse(self, q, v, lqq, lqv, lvv, stat)
    class(legacy_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: lqq(:), lqv(:), lvv(:)
    integer, intent(inout) :: stat
    integer :: nz, st
    logical :: declined
    lqq = 0.0_dp; lqv = 0.0_dp; lvv = 0.0_dp
    if (iand(self%routine%iopt, IOPT_SPARSE_HESSIANS) == 0) then
      call self%not_provided(stat); return
    end if
    nz = size(lqq)
    if (allocated(self%swork)) then
      if (size(self%swork) /= 3 * nz) deallocate (self%swork)
    end if
    if (.not. allocated(self%swork)) then
      allocate (self%swork(max(1, 3 * nz)), stat=st)
      if (st /= 0) then
        stat = -1; return        ! (unrecoverable: the step stops, naming hessians)
      end if
    end if
    call call_task(self%routine, self%n, self%m, self%n_gaps, TASK_L_HESSIANS_SPARSE, q, v, 0.0_dp, self%swork, &
                   3 * nz, stat, declined)
    if (declined) call decline(self, stat)
    lqq = self%swork(1:nz); lqv = self%swork(nz + 1:2 * nz); lvv = self%swork(2 * nz + 1:3 * nz)
  end subroutine ll_hessians_sparse

  subroutine ll_forms(self, q, omega, stat)
    class(legacy_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: omega(:, :)
    integer, intent(inout) :: stat
    call ll_task(self, TASK_FORMS, q, q, omega, size(omega), stat)
  end subroutine ll_forms

  subroutine ll_gaps(self, q, g, stat)
    class(legacy_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    call ll_task(self, TASK_GAPS, q, q, g, size(g), stat)
  end subroutine ll_gaps

  subroutine ll_gap_grads(self, q, dg, stat)
    class(legacy_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    if (iand(self%routine%iopt, IOPT_GAP_GRADS) == 0) then
      dg = 0.0_dp; call self%not_provided(stat); return
    end if
    call ll_task(self, TASK_GAP_GRADS, q, q, dg, size(dg), stat)
  end subroutine ll_gap_grads

  !> H(Q, P); without it (IOPT bit 4 unset, or answered not provided) the library inverts dL/dV.
  subroutine ll_energy(self, q, p, e, stat)
    class(legacy_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    real(dp) :: tmp(1)
    e = 0.0_dp
    if (iand(self%routine%iopt, IOPT_ENERGY) == 0) then
      call self%not_provided(stat); return
    end if
    tmp = 0.0_dp
    call ll_task(self, TASK_ENERGY, q, p, tmp, 1, stat)
    e = tmp(1)
  end subroutine ll_energy

  ! ---------------------------------------------------------------------------------------------
  ! the separable model: V's tasks, through the same dispatch and record (H is passed as 0)

  !> One task of the separable model, with the not-provided answer marked on it.
  subroutine ls_task(self, task, q, out, nout, stat)
    class(legacy_separable_t), intent(inout) :: self
    integer, intent(in) :: task, nout
    real(dp), intent(in) :: q(:)
    real(dp), intent(inout) :: out(*)
    integer, intent(inout) :: stat
    logical :: declined
    call call_task(self%routine, self%n, self%m, self%n_gaps, task, q, q, 0.0_dp, out, nout, stat, declined)
    if (declined) call decline(self, stat)
  end subroutine ls_task

  subroutine ls_potential(self, q, v, stat)
    class(legacy_separable_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: v
    integer, intent(inout) :: stat
    real(dp) :: tmp(1)
    tmp = 0.0_dp
    call ls_task(self, TASK_POTENTIAL, q, tmp, 1, stat)
    v = tmp(1)
  end subroutine ls_potential

  subroutine ls_gradient(self, q, dv, stat)
    class(legacy_separable_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dv(:)
    integer, intent(inout) :: stat
    call ls_task(self, TASK_POTENTIAL_GRAD, q, dv, size(dv), stat)
  end subroutine ls_gradient

  subroutine ls_hessian(self, q, hv, stat)
    class(legacy_separable_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: hv(:, :)
    integer, intent(inout) :: stat
    if (iand(self%routine%iopt, IOPT_HESSIAN) == 0) then
      hv = 0.0_dp; call self%not_provided(stat); return
    end if
    call ls_task(self, TASK_POTENTIAL_HESSIAN, q, hv, size(hv), stat)
  end subroutine ls_hessian

  subroutine ls_gaps(self, q, g, stat)
    class(legacy_separable_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    call ls_task(self, TASK_GAPS, q, g, size(g), stat)
  end subroutine ls_gaps

  subroutine ls_gap_grads(self, q, dg, stat)
    class(legacy_separable_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    call ls_task(self, TASK_GAP_GRADS, q, dg, size(dg), stat)
  end subroutine ls_gap_grads

  !> TASK 17 once: M from the routine into the separable model (diagonal, or dense with IOPT bit
  !> 32), checked by set_mass_* (positive / symmetric positive definite, finite). stat and, on
  !> failure, global_message say why.
  subroutine legacy_mass(sep, stat)
    type(legacy_separable_t), intent(inout) :: sep
    integer, intent(out) :: stat
    real(dp), allocatable :: mass(:)
    integer :: n, nm, code
    logical :: declined, dense
    n = sep%n
    dense = iand(sep%routine%iopt, IOPT_DENSE_MASS) /= 0
    nm = merge(n * n, n, dense)
    allocate (mass(nm), stat=stat)
    if (stat /= 0) then
      global_message = 'VCINEW: cannot allocate the mass matrix (out of memory)'
      stat = VCI_ERR_MEMORY; return
    end if
    code = 0
    call call_task(sep%routine, n, sep%m, sep%n_gaps, TASK_MASS, sep%routine%q(1:n) * 0.0_dp, &
                   sep%routine%q(1:n) * 0.0_dp, 0.0_dp, mass, nm, code, declined)
    if (code /= 0) then
      write (global_message, '(a,i0)') 'VCINEW: MODEL with TASK = 17 (the mass matrix) returned IERR = ', code
      stat = VCI_ERR_CALLBACK; return
    end if
    if (dense) then
      call sep%set_mass_matrix(reshape(mass, [n, n]), stat)
      if (stat == VCI_ERR_ARGUMENT) global_message = 'VCINEW: the mass matrix of TASK 17 is not symmetric '// &
                                                     'positive definite and finite'
    else
      call sep%set_mass_diagonal(mass, stat)
      if (stat == VCI_ERR_ARGUMENT) global_message = 'VCINEW: a diagonal mass entry of TASK 17 is not '// &
                                                     'positive and finite'
    end if
    if (stat == VCI_ERR_MEMORY) global_message = 'VCINEW: cannot allocate the mass matrix (out of memory)'
  end subroutine legacy_mass

  subroutine log_impact(self, impact, stat)
    class(impact_log_t), intent(inout) :: self
    type(vci_impact_t), intent(in) :: impact
    integer, intent(inout) :: stat
    self%count = self%count + 1
    if (self%count <= size(self%times)) self%times(self%count) = impact%t
    if (has_writer(self)) call self%out%writer%on_impact(impact, stat)
  end subroutine log_impact

  pure logical function has_writer(self)
    class(impact_log_t), intent(in) :: self
    has_writer = associated(self%out)
    if (has_writer) has_writer = allocated(self%out%writer)
  end function has_writer

  !> The file's run starts with the first VCIADV after VCIOUT (later ones continue it).
  subroutine log_start(self, info, q, p, stat)
    class(impact_log_t), intent(inout) :: self
    type(vci_run_info_t), intent(in) :: info
    real(dp), intent(in) :: q(:), p(:)
    integer, intent(inout) :: stat
    if (.not. has_writer(self)) return
    if (self%out%started) return
    call self%out%writer%on_start(info, q, p, stat)
    self%out%started = .true.
    self%out%direction = info%direction
  end subroutine log_start

  ! checkpoints go to the file (HDF5 keeps them: VCIRST from it continues bit for bit)
  pure logical function log_keeps_checkpoints(self)
    class(impact_log_t), intent(in) :: self
    log_keeps_checkpoints = .false.
    if (has_writer(self)) log_keeps_checkpoints = self%out%writer%keeps_checkpoints()
  end function log_keeps_checkpoints

  pure logical function log_wants_checkpoint(self)
    class(impact_log_t), intent(in) :: self
    log_wants_checkpoint = .false.
    if (has_writer(self)) log_wants_checkpoint = self%out%writer%wants_checkpoint()
  end function log_wants_checkpoint

  subroutine log_checkpoint(self, cp, stat)
    class(impact_log_t), intent(inout) :: self
    type(vci_checkpoint_t), intent(in) :: cp
    integer, intent(inout) :: stat
    if (has_writer(self)) call self%out%writer%on_checkpoint(cp, stat)
  end subroutine log_checkpoint

  subroutine log_failure_cause(self, cause)
    class(impact_log_t), intent(in) :: self
    character(len=*), intent(out) :: cause
    cause = ''
    if (has_writer(self)) call self%out%writer%failure_cause(cause)
  end subroutine log_failure_cause

  !> An accepted step: a failure the line search absorbed in it is no cause of a later failure.
  subroutine log_step(self, step, t, q, p, lambda, energy, stat)
    class(impact_log_t), intent(inout) :: self
    integer(i8), intent(in) :: step
    real(dp), intent(in) :: t, q(:), p(:), lambda(:), energy
    integer, intent(inout) :: stat
    if (associated(self%record)) call self%record%clear()
    if (has_writer(self)) call self%out%writer%on_step(step, t, q, p, lambda, energy, stat)
  end subroutine log_step

  ! ---------------------------------------------------------------------------------------------
  ! the handle table behind the external routines

  !> IOPT bit 16's own refusals (global_message says why): with bit 8 or 4 (H is derived from M
  !> and V), M > 0 (a separable model has no nonholonomic constraints), NG > 0 without the gap
  !> gradients (bit 2), bit 32 without bit 16, or TASK 17's N*N beyond an integer.
  logical function separable_refused(n, m, ng, iopt, stat) result(refused)
    integer, intent(in) :: n, m, ng, iopt
    integer, intent(out) :: stat
    refused = .true.
    stat = VCI_ERR_ARGUMENT
    if (iand(iopt, IOPT_SEPARABLE) == 0) then
      refused = iand(iopt, IOPT_DENSE_MASS) /= 0
      if (refused) global_message = 'VCINEW: IOPT bit 32 (dense M) is for a separable model (bit 16)'
    else if (iand(iopt, IOPT_CONTINUOUS + IOPT_ENERGY) /= 0) then
      global_message = 'VCINEW: IOPT bit 16 (separable L) excludes bit 8 (general L) and bit 4 (H: it is '// &
                       'derived from M and V)'
    else if (m /= 0) then
      write (global_message, '(a,i0,a)') 'VCINEW: M = ', m, ' but a separable model (IOPT bit 16) has no '// &
        'nonholonomic constraints (the explicit schemes cannot impose them): give it as a continuous L (bit 8)'
    else if (ng > 0 .and. iand(iopt, IOPT_GAP_GRADS) == 0) then
      global_message = 'VCINEW: a separable model with walls (NG > 0) needs TASK 8, the gap gradients (IOPT bit 2)'
    else if (iand(iopt, IOPT_DENSE_MASS) /= 0 .and. vci_size_problem(n, m, ng) == '' .and. &
             int(n, i8) * n > int(huge(1), i8)) then
      write (global_message, '(a,i0,a)') 'VCINEW: N = ', n, ' too large for TASK 17 (need N*N < 2**31)'
    else
      refused = .false.; stat = VCI_OK
    end if
  end function separable_refused

  !> Create model and integrator; ih > 0 on success, 0 on failure (message for VCIMSG(0, ...)).
  !> IOPT bit 8: the routine is a continuous L (scheme midpoint until VCISCH), else a discrete L_d.
  subroutine legacy_new(fn, n, m, ng, iopt, h, rpar, ipar, ih, stat)
    procedure(vci_legacy_model_fn) :: fn
    integer, intent(in) :: n, m, ng, iopt
    real(dp), intent(in) :: h
    type(c_ptr), intent(in) :: rpar, ipar
    integer, intent(out) :: ih, stat
    type(slot_t), allocatable :: grown(:)
    type(legacy_routine_t) :: routine
    integer :: i
    ih = 0
    if (iopt < 0 .or. iopt > IOPT_HESSIAN + IOPT_GAP_GRADS + IOPT_ENERGY + IOPT_CONTINUOUS + IOPT_SEPARABLE + &
        IOPT_DENSE_MASS + IOPT_BAND_HESSIANS + IOPT_LD_FUSED + IOPT_SPARSE_HESSIANS) then
      write (global_message, '(a,i0,a)') 'VCINEW: IOPT = ', iopt, &
        ' (need a sum of 1: Hessian, 2: gap gradients, 4: energy, 8: continuous L, 16: separable L, 32: dense M,'// &
        ' 64: banded Hessians, 128: fused L_d, 256: sparse Hessians)'
      stat = VCI_ERR_ARGUMENT; return
    end if
    if (iand(iopt, IOPT_LD_FUSED) /= 0 .and. iand(iopt, IOPT_CONTINUOUS + IOPT_SEPARABLE) /= 0) then
      global_message = 'VCINEW: IOPT bit 128 (TASK 19, a discrete L_d''s fused task) with bit 8 or 16 '// &
                       '(a continuous or separable L)'
      stat = VCI_ERR_ARGUMENT; return
    end if
    if (iand(iopt, IOPT_LD_FUSED) /= 0 .and. vci_size_problem(n, m, ng) == '' .and. &
        2 * int(n, i8) + 1 + int(n, i8) * n > int(huge(1), i8)) then
      write (global_message, '(a,i0,a)') 'VCINEW: N = ', n, ' too large for TASK 19 (need 2*N+1+N*N < 2**31)'
      stat = VCI_ERR_ARGUMENT; return
    end if
    if (iand(iopt, IOPT_BAND_HESSIANS) /= 0 .and. iand(iopt, IOPT_CONTINUOUS + IOPT_SEPARABLE) /= IOPT_CONTINUOUS) then
      global_message = 'VCINEW: IOPT bit 64 (TASK 18, banded Hessians of L) needs a continuous L (bit 8, not 16)'
      stat = VCI_ERR_ARGUMENT; return
    end if
    if (iand(iopt, IOPT_SPARSE_HESSIANS) /= 0 .and. iand(iopt, IOPT_CONTINUOUS + IOPT_SEPARABLE) /= IOPT_CONTINUOUS) then
      global_message = 'VCINEW: IOPT bit 256 (TASK 20, sparse Hessians of L) needs a continuous L (bit 8, not 16)'
      stat = VCI_ERR_ARGUMENT; return
    end if
    if (separable_refused(n, m, ng, iopt, stat)) return
    if (iand(iopt, IOPT_CONTINUOUS + IOPT_HESSIAN) == IOPT_CONTINUOUS + IOPT_HESSIAN .and. &
        vci_size_problem(n, m, ng) == '' .and. 3 * int(n, i8) * n > int(huge(1), i8)) then
      write (global_message, '(a,i0,a)') 'VCINEW: N = ', n, ' too large for TASK 13 (need 3*N*N < 2**31)'
      stat = VCI_ERR_ARGUMENT; return
    end if
    routine%fn => fn
    routine%iopt = iopt
    routine%rpar = rpar; routine%ipar = ipar
    if (vci_size_problem(n, m, ng) == '') then
      allocate (routine%q(n), routine%v(n), stat=stat)
      if (stat /= 0) then
        global_message = 'VCINEW: cannot allocate the copies of Q and V (out of memory)'
        stat = VCI_ERR_MEMORY; return
      end if
    end if
    if (.not. allocated(slots)) then
      allocate (slots(4), stat=stat)
      if (stat /= 0) then
        global_message = 'VCINEW: cannot allocate the handle table (out of memory)'
        stat = VCI_ERR_MEMORY; return
      end if
    end if
    i = findloc(slots%id, 0, dim=1)
    if (i == 0) then
      allocate (grown(2 * size(slots)), stat=stat)
      if (stat /= 0) then
        global_message = 'VCINEW: cannot grow the handle table (out of memory)'
        stat = VCI_ERR_MEMORY; return
      end if
      grown(1:size(slots)) = slots
      i = size(slots) + 1
      call move_alloc(grown, slots)
    end if
    if (iand(iopt, IOPT_SEPARABLE) /= 0) then
      allocate (slots(i)%sep, slots(i)%integ, stat=stat)
    else if (iand(iopt, IOPT_CONTINUOUS) /= 0) then
      allocate (slots(i)%lag, slots(i)%integ, stat=stat)
      if (stat == 0 .and. iand(iopt, IOPT_HESSIAN) /= 0 .and. vci_size_problem(n, m, ng) == '') &
        allocate (slots(i)%lag%hwork(3 * n * n), stat=stat)
    else
      allocate (slots(i)%model, slots(i)%integ, stat=stat)
      if (stat == 0 .and. iand(iopt, IOPT_LD_FUSED) /= 0 .and. vci_size_problem(n, m, ng) == '') &
        allocate (slots(i)%model%fwork(2 * n + 1 + n * n), stat=stat)
    end if
    if (stat /= 0) then
      global_message = 'VCINEW: cannot allocate the model (out of memory)'
      call free_slot(i)
      stat = VCI_ERR_MEMORY; return
    end if
    if (associated(slots(i)%sep)) then
      slots(i)%sep%n = n; slots(i)%sep%m = m; slots(i)%sep%n_gaps = ng
      slots(i)%sep%routine = routine
      stat = VCI_OK
      if (vci_size_problem(n, m, ng) == '') call legacy_mass(slots(i)%sep, stat)
      if (stat /= VCI_OK) then
        call free_slot(i); return
      end if
      call slots(i)%integ%create(slots(i)%sep, h, stat)
    else if (associated(slots(i)%lag)) then
      slots(i)%lag%n = n; slots(i)%lag%m = m; slots(i)%lag%n_gaps = ng
      slots(i)%lag%routine = routine
      call slots(i)%integ%create(slots(i)%lag, h, stat)
    else
      slots(i)%model%n = n; slots(i)%model%m = m; slots(i)%model%n_gaps = ng
      slots(i)%model%routine = routine
      call slots(i)%integ%create(slots(i)%model, h, stat)
    end if
    if (stat /= VCI_OK) then
      global_message = 'VCINEW: '//trim(slots(i)%integ%message_text())
      ! a required TASK answered "not provided": name it
      if (associated(slots(i)%lag)) then
        if (slots(i)%lag%routine%record%code == IERR_NOT_PROVIDED) &
          global_message = trim(global_message)//' ('//trim(slots(i)%lag%routine%record%failed)//')'
      end if
      call free_slot(i)
      return
    end if
    last_id = last_id + 1
    slots(i)%id = last_id
    ih = last_id
  end subroutine legacy_new

  !> Free what slot i holds and mark it free; the table goes when nothing is left in it.
  subroutine free_slot(i)
    integer, intent(in) :: i
    integer :: stat
    if (associated(slots(i)%out)) stat = close_output(i)
    if (associated(slots(i)%integ)) deallocate (slots(i)%integ)
    if (associated(slots(i)%model)) deallocate (slots(i)%model)
    if (associated(slots(i)%lag)) deallocate (slots(i)%lag)
    if (associated(slots(i)%sep)) deallocate (slots(i)%sep)
    slots(i)%id = 0
    if (all(slots%id == 0)) deallocate (slots)   ! nothing left behind at exit
  end subroutine free_slot

  !> The slot of handle ih (0 if none).
  !> n of the model of handle ih (0 when none).
  integer function legacy_size(ih)
    integer, intent(in) :: ih
    integer :: i
    legacy_size = 0
    i = slot_of(ih)
    if (i == 0) return
    legacy_size = slots(i)%integ%n_coordinates()
  end function legacy_size

  integer function slot_of(ih)
    integer, intent(in) :: ih
    slot_of = 0
    if (ih > 0 .and. allocated(slots)) slot_of = findloc(slots%id, ih, dim=1)
  end function slot_of

  !> The callback record of slot i's model, whichever kind it is.
  function slot_record(i) result(record)
    integer, intent(in) :: i
    type(vci_callback_record_t), pointer :: record
    if (associated(slots(i)%sep)) then
      record => slots(i)%sep%routine%record
    else if (associated(slots(i)%lag)) then
      record => slots(i)%lag%routine%record
    else
      record => slots(i)%model%routine%record
    end if
  end function slot_record

  !> The integrator named ih; null (stat = VCI_ERR_ARGUMENT, message for VCIMSG(0, ...)) if none.
  subroutine legacy_get(ih, who, integ, stat)
    integer, intent(in) :: ih
    character(len=*), intent(in) :: who
    type(vci_integrator_t), pointer, intent(out) :: integ
    integer, intent(out) :: stat
    type(vci_callback_record_t), pointer :: record
    integer :: i
    integ => null()
    i = slot_of(ih)
    if (i == 0) then
      write (global_message, '(a,i0,a)') who//': IH = ', ih, ' names no live integrator (deleted, or VCINEW failed)'
      stat = VCI_ERR_ARGUMENT; return
    end if
    integ => slots(i)%integ
    call integ%report_failure(VCI_OK, '')
    record => slot_record(i)
    call record%clear()
    stat = VCI_OK
  end subroutine legacy_get

  !> VCICHK: the model checker on the model of handle ih at (q, v, h) (v: the second point of L_d,
  !> or the velocity of L); ipass = 1 when every supplied derivative agrees within tol (<= 0: 1e-6).
  subroutine legacy_check(ih, q, v, h, tol, ipass, worst, stat)
    integer, intent(in) :: ih
    real(dp), intent(in) :: q(:), v(:), h, tol
    integer, intent(out) :: ipass
    real(dp), intent(out) :: worst
    integer, intent(out) :: stat
    type(vci_integrator_t), pointer :: integ
    type(vci_check_report_t) :: rep
    character(len=VCI_MSG_LEN) :: msg
    real(dp) :: t
    integer :: i
    ipass = 0; worst = 0.0_dp
    call legacy_get(ih, 'VCICHK', integ, stat)
    if (stat /= VCI_OK) return
    i = slot_of(ih)
    t = rep%tol
    if (tol > 0.0_dp) t = tol
    if (associated(slots(i)%sep)) then
      call vci_check_model(slots(i)%sep, q, v, h, rep, stat, msg, tol=t)
    else if (associated(slots(i)%lag)) then
      call vci_check_model(slots(i)%lag, q, v, h, rep, stat, msg, tol=t)
    else
      call vci_check_model(slots(i)%model, q, v, h, rep, stat, msg, tol=t)
    end if
    if (stat /= VCI_OK) then
      call integ%report_failure(stat, msg); return
    end if
    ipass = merge(1, 0, rep%passed); worst = rep%worst
    if (.not. rep%passed) then
      do i = 1, rep%count
        if (rep%items(i)%checked .and. rep%items(i)%mismatch > rep%tol) then
          write (msg, '(a,es9.2,a)') 'VCICHK: '//trim(rep%items(i)%name)//' against '//trim(rep%items(i)%against)// &
            ': mismatch ', rep%items(i)%mismatch, ' (first of the failed comparisons)'
          exit
        end if
      end do
      call integ%report_failure(VCI_OK, msg)
    end if
  end subroutine legacy_check

  !> After a call into the integrator: name the failing TASK and its IERR (the shared adapter).
  subroutine legacy_after(ih, stat)
    integer, intent(in) :: ih
    integer, intent(inout) :: stat
    type(vci_callback_record_t), pointer :: record
    integer :: i
    character(len=VCI_MSG_LEN) :: msg
    i = slot_of(ih)
    if (i == 0) return
    msg = slots(i)%integ%message_text()
    record => slot_record(i)
    call record%annotate(stat, msg)
    call slots(i)%integ%report_failure(stat, msg)
  end subroutine legacy_after

  !> VCIINP and VCIINM: start the integrator named ih from (q0 at t0, x1 = q1 at t0 + h) with
  !> from_pair, else from (q0, x1 = p0) at t0; the arrays are the caller's assumed-size ones.
  subroutine legacy_init(ih, who, from_pair, t0, q0, x1, stat)
    integer, intent(in) :: ih
    character(len=*), intent(in) :: who
    logical, intent(in) :: from_pair
    real(dp), intent(in) :: t0, q0(*), x1(*)
    integer, intent(out) :: stat
    type(vci_integrator_t), pointer :: integ
    integer :: n
    call legacy_get(ih, who, integ, stat)
    if (stat /= VCI_OK) return
    if (output_blocks_start(slot_of(ih), who, stat)) return
    n = integ%n_coordinates()
    if (from_pair) then
      call integ%init_from_pair(t0, q0(1:n), x1(1:n), stat)
    else
      call integ%init_from_momentum(t0, q0(1:n), x1(1:n), stat)
    end if
    call legacy_after(ih, stat)
  end subroutine legacy_init

  !> Choose the scheme of the continuous model named ih (live: legacy_get succeeded).
  subroutine legacy_set_scheme(ih, scheme, stages, stat)
    integer, intent(in) :: ih, scheme, stages
    integer, intent(out) :: stat
    integer :: i
    i = slot_of(ih)
    if (.not. (associated(slots(i)%lag) .or. associated(slots(i)%sep))) then
      call slots(i)%integ%report_failure(VCI_ERR_ARGUMENT, 'VCISCH: the model is a discrete L_d (IOPT without '// &
                                         'bit 8 or 16); schemes discretise a continuous L (IOPT + 8 or + 16 at VCINEW)')
      stat = VCI_ERR_ARGUMENT; return
    end if
    call slots(i)%integ%set_scheme(scheme, stages, stat)
    if (stat /= VCI_OK) call slots(i)%integ%report_failure(stat, 'VCISCH: '//trim(slots(i)%integ%message_text()))
  end subroutine legacy_set_scheme

  !> VCIBND: declare the model's Hessians banded (bw < 0: dense) with the debug check when check,
  !> then rebuild the current scheme with it (so before VCIINP / VCIINM, as VCISCH).
  subroutine legacy_bandwidth(ih, bw, check, stat)
    integer, intent(in) :: ih, bw
    logical, intent(in) :: check
    integer, intent(out) :: stat
    integer :: i
    i = slot_of(ih)
    if (associated(slots(i)%sep)) then
      call slots(i)%integ%report_failure(VCI_ERR_ARGUMENT, 'VCIBND: a separable model (IOPT bit 16) has no '// &
                                         'declared bandwidth')
      stat = VCI_ERR_ARGUMENT; return
    end if
    if (associated(slots(i)%lag)) then
      call slots(i)%lag%declare_bandwidth(bw, check)
    else
      call slots(i)%model%declare_bandwidth(bw, check)
    end if
    associate (integ => slots(i)%integ)
      call integ%set_scheme(integ%scheme(), integ%stages(), stat)
      if (stat /= VCI_OK) call integ%report_failure(stat, 'VCIBND: '//trim(integ%message_text()))
    end associate
  end subroutine legacy_bandwidth

  !> VCIPAT: declare the model's Hessians sparse with the 1-based pattern (icolp(n + 1), irow(nnz)),
  !> checked strictly (nnz < 0: withdrawn), with the debug check when check, then rebuild the
  !> current scheme with it (so before VCIINP / VCIINM, as VCIBND).
  subroutine legacy_pattern(ih, nnz, icolp, irow, check, stat)
    integer, intent(in) :: ih, nnz, icolp(*), irow(*)
    logical, intent(in) :: check
    integer, intent(out) :: stat
    character(len=200) :: why
    integer :: i, n
    i = slot_of(ih)
    stat = VCI_ERR_ARGUMENT
    why = ''
    if (associated(slots(i)%sep)) then
      why = 'a separable model (IOPT bit 16) has no declared pattern'
    else if (associated(slots(i)%lag)) then
      n = slots(i)%lag%n
    else
      n = slots(i)%model%n
    end if
    if (why == '' .and. nnz >= 0) then
      if (.not. sparse_available()) then
        why = 'this vci was built without the sparse solver (CMake VCI_SPARSE=OFF; SuiteSparse KLU)'
      else if (icolp(n + 1) /= nnz + 1) then
        write (why, '(a,i0,a,i0,a)') 'ICOLP(N+1) = ', icolp(n + 1), ', not NNZ + 1 = ', nnz + 1, ''
      else
        call pattern_arrays_error(n, icolp(1:n + 1), irow(1:nnz), 1, 'ICOLP', 'IROW', why)
      end if
    end if
    if (why /= '') then
      call slots(i)%integ%report_failure(VCI_ERR_ARGUMENT, 'VCIPAT: '//trim(why)); return
    end if
    if (associated(slots(i)%lag)) then
      if (nnz >= 0) then
        call slots(i)%lag%declare_pattern(icolp(1:n + 1), irow(1:nnz), check)
      else
        call slots(i)%lag%declare_pattern([integer ::], [integer ::])
      end if
    else
      if (nnz >= 0) then
        call slots(i)%model%declare_pattern(icolp(1:n + 1), irow(1:nnz), check)
      else
        call slots(i)%model%declare_pattern([integer ::], [integer ::])
      end if
    end if
    associate (integ => slots(i)%integ)
      call integ%set_scheme(integ%scheme(), integ%stages(), stat)
      if (stat /= VCI_OK) call integ%report_failure(stat, 'VCIPAT: '//trim(integ%message_text()))
    end associate
  end subroutine legacy_pattern

  !> Free the integrator named ih (no-op if none); ih becomes 0.
  subroutine legacy_delete(ih)
    integer, intent(inout) :: ih
    integer :: i
    i = slot_of(ih)
    if (i > 0) call free_slot(i)
    ih = 0
  end subroutine legacy_delete

  !> nsteps steps in direction idir on the integrator named ih (live: legacy_get succeeded); the
  !> state and the impact times of this call out.
  subroutine legacy_advance(ih, nsteps, idir, t, q, p, nimp, timp, stat)
    integer, intent(in) :: ih, nsteps, idir
    real(dp), intent(inout) :: t, q(:), p(:), timp(:)
    integer, intent(out) :: nimp, stat
    type(impact_log_t) :: log
    integer :: k, i
    i = slot_of(ih)
    allocate (log%times(size(timp)), stat=stat)
    if (stat /= 0) then
      nimp = 0
      call slots(i)%integ%report_failure(VCI_ERR_MEMORY, 'VCIADV: cannot allocate the impact log (out of memory)')
      stat = VCI_ERR_MEMORY; return
    end if
    log%record => slot_record(i)
    log%out => slots(i)%out
    if (associated(log%out)) then
      if (log%out%started .and. (idir == 1 .or. idir == -1) .and. idir /= log%out%direction) then
        nimp = 0
        call slots(i)%integ%report_failure(VCI_ERR_STATE, 'VCIADV: the output file (VCIOUT) holds a run in the '// &
          'other direction; close it (VCICLS) or open a new one to integrate this way')
        stat = VCI_ERR_STATE; return
      end if
    end if
    associate (integ => slots(i)%integ)
      call integ%integrate(int(nsteps, i8), idir, stat, log)
      if (associated(log%out)) then
        if (log%out%started) then
          log%out%run_status = stat
          log%out%run_message = ''
          if (stat /= VCI_OK) log%out%run_message = integ%message_text()
        end if
      end if
      nimp = log%count
      k = min(nimp, size(timp))
      timp(1:k) = log%times(1:k)
      if (integ%is_initialized()) then
        t = integ%time(); q = integ%configuration(); p = integ%momentum()
      end if
    end associate
  end subroutine legacy_advance

  !> An output file holds one run from one start: no new start (VCIINP, VCIINM, VCIRST) while it
  !> has steps.
  logical function output_blocks_start(i, who, stat) result(blocked)
    integer, intent(in) :: i
    character(len=*), intent(in) :: who
    integer, intent(inout) :: stat
    blocked = .false.
    if (associated(slots(i)%out)) blocked = slots(i)%out%started
    if (blocked) then
      call slots(i)%integ%forget_state()
      call slots(i)%integ%report_failure(VCI_ERR_STATE, who//': the output file (VCIOUT) holds the run so far; '// &
                                         'close it (VCICLS) or open a new one before starting again')
      stat = VCI_ERR_STATE
    end if
  end function output_blocks_start

  !> Finish and drop the output file of slot i (its last state's checkpoint first); its status.
  integer function close_output(i) result(stat)
    integer, intent(in) :: i
    integer :: cstat
    stat = VCI_OK
    if (.not. associated(slots(i)%out)) return
    cstat = VCI_OK
    if (allocated(slots(i)%out%writer)) then
      associate (w => slots(i)%out%writer)
        ! (no memory for the checkpoint: the file is still finished, without it)
        if (slots(i)%out%started .and. w%keeps_checkpoints()) then
          call slots(i)%integ%checkpoint_to(w, cstat)
        end if
        stat = VCI_OK
        call w%on_finish(slots(i)%out%run_status, trim(slots(i)%out%run_message), stat)
        if (stat /= VCI_OK) call w%failure_cause(global_message)
      end associate
    end if
    deallocate (slots(i)%out)
    if (stat /= VCI_OK) stat = VCI_ERR_IO
    if (stat == VCI_OK .and. cstat == VCI_ERR_MEMORY) then
      stat = VCI_ERR_MEMORY
      global_message = 'the output file was finished without its last state''s checkpoint: no memory for it'
    end if
  end function close_output

  !> VCIOUT: write the later steps of ih (live) to the HDF5 file path (replaced), or with append
  !> continue it (the run must go on from its last state: VCIRST).
  subroutine legacy_open_output(ih, path, append, stat)
    integer, intent(in) :: ih
    character(len=*), intent(in) :: path
    logical, intent(in) :: append
    integer, intent(out) :: stat
    character(len=VCI_MSG_LEN) :: msg
    integer :: i
    i = slot_of(ih)
    if (len_trim(path) == 0) then
      call slots(i)%integ%report_failure(VCI_ERR_ARGUMENT, 'VCIOUT: PATH is blank'); stat = VCI_ERR_ARGUMENT
      return
    end if
    stat = close_output(i)
    if (stat /= VCI_OK) then
      call slots(i)%integ%report_failure(stat, 'VCIOUT: the previous output file could not be finished: '// &
                                         trim(global_message))
      return
    end if
    allocate (slots(i)%out, stat=stat)
    if (stat /= 0) then
      call slots(i)%integ%report_failure(VCI_ERR_MEMORY, 'VCIOUT: out of memory'); stat = VCI_ERR_MEMORY; return
    end if
    call bindings_open_h5(trim(path), append, slots(i)%out%writer, stat, msg)
    if (stat /= VCI_OK) then
      deallocate (slots(i)%out)
      call slots(i)%integ%report_failure(stat, 'VCIOUT: '//trim(msg))
    end if
  end subroutine legacy_open_output

  !> VCICLS: finish and close the output file of ih (live), if any.
  subroutine legacy_close_output(ih, stat)
    integer, intent(in) :: ih
    integer, intent(out) :: stat
    integer :: i
    i = slot_of(ih)
    global_message = ''
    stat = close_output(i)
    if (stat /= VCI_OK) call slots(i)%integ%report_failure(stat, 'VCICLS: the output file could not be finished: '// &
                                                             trim(global_message))
  end subroutine legacy_close_output

  !> VCIRST: start ih (live) from the last state of the HDF5 file path: bit for bit from the
  !> checkpoint the file keeps; the file's n, m and h must be the integrator's.
  subroutine legacy_restore(ih, path, stat)
    integer, intent(in) :: ih
    character(len=*), intent(in) :: path
    integer, intent(out) :: stat
    type(vci_checkpoint_t) :: cp
    character(len=VCI_MSG_LEN) :: msg
    character(len=160) :: why
    integer :: i
    i = slot_of(ih)
    stat = VCI_OK
    if (output_blocks_start(i, 'VCIRST', stat)) return
    associate (integ => slots(i)%integ)
      if (len_trim(path) == 0) then
        call integ%forget_state()
        call integ%report_failure(VCI_ERR_ARGUMENT, 'VCIRST: PATH is blank'); stat = VCI_ERR_ARGUMENT; return
      end if
      call bindings_read_h5(trim(path), cp, stat, msg)
      if (stat /= VCI_OK) then
        call integ%forget_state()
        call integ%report_failure(stat, 'VCIRST: '//trim(msg)); return
      end if
      if (size(cp%q) /= integ%n_coordinates() .or. size(cp%lambda) /= integ%n_constraints() .or. &
          cp%h /= integ%step_length()) then
        call integ%forget_state()
        write (why, '(2(a,i0),a,es24.17,2(a,i0),a,es24.17,a)') ': the file holds n = ', size(cp%q), ', m = ', &
          size(cp%lambda), ', h = ', cp%h, '; the integrator has N = ', integ%n_coordinates(), ', M = ', &
          integ%n_constraints(), ', H = ', integ%step_length(), ' (another model or step length)'
        call integ%report_failure(VCI_ERR_ARGUMENT, 'VCIRST: '//trim(path)//trim(why)); stat = VCI_ERR_ARGUMENT
        return
      end if
      call integ%restore(cp, stat)
    end associate
    call legacy_after(ih, stat)
  end subroutine legacy_restore

  !> The message of the last call on ih, or of the last failure without a live handle.
  function legacy_message(ih) result(msg)
    integer, intent(in) :: ih
    character(len=VCI_MSG_LEN) :: msg
    integer :: i
    msg = global_message
    i = slot_of(ih)
    if (i > 0) msg = slots(i)%integ%message_text()
  end function legacy_message
end module vci_legacy

! -------------------------------------------------------------------------------------------------
! The external routines: no module needed by the caller. Arrays have the sizes of the model (N).

!> Create an integrator of step H over the EXTERNAL routine MODEL; IH > 0 names it. RPAR and IPAR
!> are handed to MODEL on every call and must stay in place until VCIDEL.
subroutine vcinew(model, n, m, ng, iopt, h, rpar, ipar, ih, istat)
  use, intrinsic :: iso_c_binding, only: c_loc
  use vci_kinds, only: dp
  use vci_legacy, only: vci_legacy_model_fn, legacy_new
  implicit none
  procedure(vci_legacy_model_fn) :: model
  integer, intent(in) :: n, m, ng, iopt
  real(dp), intent(in) :: h
  real(dp), target, intent(inout) :: rpar(*)
  integer, target, intent(inout) :: ipar(*)
  integer, intent(out) :: ih, istat
  call legacy_new(model, n, m, ng, iopt, h, c_loc(rpar(1)), c_loc(ipar(1)), ih, istat)
end subroutine vcinew

!> Newton tolerances: |r_i| <= ATOL + RTOL * (size of row i's terms); at most MAXIT iterations.
subroutine vcitol(ih, atol, rtol, maxit, istat)
  use vci_kinds, only: dp
  use vci_status, only: VCI_OK
  use vci_integrator, only: vci_integrator_t
  use vci_legacy, only: legacy_get
  implicit none
  integer, intent(in) :: ih, maxit
  real(dp), intent(in) :: atol, rtol
  integer, intent(out) :: istat
  type(vci_integrator_t), pointer :: integ
  call legacy_get(ih, 'VCITOL', integ, istat)
  if (istat == VCI_OK) call integ%set_tolerances(atol, rtol, maxit, istat)
end subroutine vcitol

!> Impact energy condition: MODE 0 discrete (the paper's, default), 1 hamiltonian (IOPT bit 4, or
!> any continuous model: H by Legendre inversion of dL/dV without it).
subroutine vcieng(ih, mode, istat)
  use vci_status, only: VCI_OK
  use vci_integrator, only: vci_integrator_t
  use vci_legacy, only: legacy_get
  implicit none
  integer, intent(in) :: ih, mode
  integer, intent(out) :: istat
  type(vci_integrator_t), pointer :: integ
  call legacy_get(ih, 'VCIENG', integ, istat)
  if (istat == VCI_OK) call integ%set_impact_energy(mode, istat)
end subroutine vcieng

!> The safety net (docs/DESIGN.md §2): a step that cannot be solved is retried as 2, 4, ... equal
!> sub-steps up to MAXSPL of them (default 16); MAXSPL = 1 turns it off. ISTAT = 1 outside 1..1024.
subroutine vcispl(ih, maxspl, istat)
  use vci_status, only: VCI_OK
  use vci_integrator, only: vci_integrator_t
  use vci_legacy, only: legacy_get
  implicit none
  integer, intent(in) :: ih, maxspl
  integer, intent(out) :: istat
  type(vci_integrator_t), pointer :: integ
  call legacy_get(ih, 'VCISPL', integ, istat)
  if (istat == VCI_OK) call integ%set_step_splits(maxspl, istat)
end subroutine vcispl

!> The poke screen (docs/BACKWARD.md, "A wall poked within one sub-step"): ION = 1 (the default)
!> meets a wall crossed and left again within one sub-step, ION = 0 tests the gaps at the sub-steps'
!> ends only. ISTAT = 1 for any other ION.
subroutine vcipok(ih, ion, istat)
  use vci_status, only: VCI_OK, VCI_ERR_ARGUMENT
  use vci_integrator, only: vci_integrator_t
  use vci_legacy, only: legacy_get
  implicit none
  integer, intent(in) :: ih, ion
  integer, intent(out) :: istat
  type(vci_integrator_t), pointer :: integ
  call legacy_get(ih, 'VCIPOK', integ, istat)
  if (istat /= VCI_OK) return
  if (ion /= 0 .and. ion /= 1) then
    call integ%report_failure(VCI_ERR_ARGUMENT, 'VCIPOK: ION must be 0 or 1')
    istat = VCI_ERR_ARGUMENT; return
  end if
  call integ%set_poke_samples(ion == 1, istat)
end subroutine vcipok

!> The safety net's counts: NSPLIT steps taken as equal sub-steps, MOSTSP the most sub-steps one of
!> them needed (0 when none), over the handle's life.
subroutine vcinet(ih, nsplit, mostsp, istat)
  use vci_kinds, only: i8
  use vci_status, only: VCI_OK
  use vci_integrator, only: vci_integrator_t, vci_stats_t
  use vci_legacy, only: legacy_get
  implicit none
  integer, intent(in) :: ih
  integer, intent(out) :: nsplit, mostsp, istat
  type(vci_integrator_t), pointer :: integ
  type(vci_stats_t) :: stats
  nsplit = 0; mostsp = 0
  call legacy_get(ih, 'VCINET', integ, istat)
  if (istat /= VCI_OK) return
  stats = integ%statistics()
  nsplit = int(min(stats%split_steps, int(huge(1), i8)))
  mostsp = int(stats%largest_split)
end subroutine vcinet

!> Scheme of a continuous model (IOPT bit 8): ISCH 1 left (order 1), 2 midpoint (order 2, the
!> default), 3 lobatto with NSTG = s stages (1 <= s <= 8, order 2s, with or without constraints); NSTG is ignored
!> except for lobatto. Call after VCINEW and before VCIINP/VCIINM (the state is reset).
subroutine vcisch(ih, isch, nstg, istat)
  use vci_status, only: VCI_OK
  use vci_integrator, only: vci_integrator_t
  use vci_legacy, only: legacy_get, legacy_set_scheme, legacy_after
  implicit none
  integer, intent(in) :: ih, isch, nstg
  integer, intent(out) :: istat
  type(vci_integrator_t), pointer :: integ
  call legacy_get(ih, 'VCISCH', integ, istat)
  if (istat /= VCI_OK) return
  call legacy_set_scheme(ih, isch, nstg, istat)
  call legacy_after(ih, istat)
end subroutine vcisch

!> Declare the model's Hessians banded with half-bandwidth IBW (IBW < 0: dense again); ICHK /= 0:
!> the debug check (the band against the dense Hessians or differences at the start, and every
!> Newton matrix). The current scheme is rebuilt with it: call before VCIINP / VCIINM.
subroutine vcibnd(ih, ibw, ichk, istat)
  use vci_status, only: VCI_OK
  use vci_integrator, only: vci_integrator_t
  use vci_legacy, only: legacy_get, legacy_bandwidth, legacy_after
  implicit none
  integer, intent(in) :: ih, ibw, ichk
  integer, intent(out) :: istat
  type(vci_integrator_t), pointer :: integ
  call legacy_get(ih, 'VCIBND', integ, istat)
  if (istat /= VCI_OK) return
  call legacy_bandwidth(ih, ibw, ichk /= 0, istat)
  call legacy_after(ih, istat)
end subroutine vcibnd

!> Declare the model's Hessians sparse: the N x N pattern in compressed columns, 1-based (column
!> J's rows IROW(ICOLP(J) : ICOLP(J+1) - 1), strictly increasing; ICOLP(N+1) = NNZ + 1); NNZ < 0:
!> dense again. ICHK /= 0: the debug check of every Newton matrix against the pattern. Needs the
!> sparse solver (VCI_SPARSE); ISTAT = 1 with a message otherwise, or for a bad pattern. The
!> current scheme is rebuilt with it: call before VCIINP / VCIINM.
subroutine vcipat(ih, nnz, icolp, irow, ichk, istat)
  use vci_status, only: VCI_OK
  use vci_integrator, only: vci_integrator_t
  use vci_legacy, only: legacy_get, legacy_pattern, legacy_after
  implicit none
  integer, intent(in) :: ih, nnz, icolp(*), irow(*), ichk
  integer, intent(out) :: istat
  type(vci_integrator_t), pointer :: integ
  call legacy_get(ih, 'VCIPAT', integ, istat)
  if (istat /= VCI_OK) return
  call legacy_pattern(ih, nnz, icolp, irow, ichk /= 0, istat)
  call legacy_after(ih, istat)
end subroutine vcipat

!> Start from Q0 at T0 and Q1 at T0 + H: the state becomes (T0 + H, Q1, D2 L_d(Q0, Q1, H)).
subroutine vciinp(ih, t0, q0, q1, istat)
  use vci_kinds, only: dp
  use vci_legacy, only: legacy_init
  implicit none
  integer, intent(in) :: ih
  real(dp), intent(in) :: t0, q0(*), q1(*)
  integer, intent(out) :: istat
  call legacy_init(ih, 'VCIINP', .true., t0, q0, q1, istat)
end subroutine vciinp

!> Start from (Q0, P0) at T0.
subroutine vciinm(ih, t0, q0, p0, istat)
  use vci_kinds, only: dp
  use vci_legacy, only: legacy_init
  implicit none
  integer, intent(in) :: ih
  real(dp), intent(in) :: t0, q0(*), p0(*)
  integer, intent(out) :: istat
  call legacy_init(ih, 'VCIINM', .false., t0, q0, p0, istat)
end subroutine vciinm

!> NSTEPS steps in direction IDIR (+1 forward, -1 backward). Out: the state (T, Q(N), P(N)) (the
!> last accepted one when ISTAT /= 0), NIMP impacts in this call and the first LTIMP impact times.
subroutine vciadv(ih, nsteps, idir, t, q, p, nimp, timp, ltimp, istat)
  use vci_kinds, only: dp
  use vci_status, only: VCI_OK, VCI_ERR_ARGUMENT
  use vci_integrator, only: vci_integrator_t
  use vci_legacy, only: legacy_get, legacy_advance, legacy_after
  implicit none
  integer, intent(in) :: ih, nsteps, idir, ltimp
  real(dp), intent(inout) :: t, q(*), p(*), timp(*)
  integer, intent(out) :: nimp, istat
  type(vci_integrator_t), pointer :: integ
  character(len=64) :: msg
  integer :: n
  nimp = 0
  call legacy_get(ih, 'VCIADV', integ, istat)
  if (istat /= VCI_OK) return
  if (ltimp < 0) then
    write (msg, '(a,i0,a)') 'VCIADV: LTIMP = ', ltimp, ' (need >= 0)'
    call integ%report_failure(VCI_ERR_ARGUMENT, msg); istat = VCI_ERR_ARGUMENT; return
  end if
  n = integ%n_coordinates()
  call legacy_advance(ih, nsteps, idir, t, q(1:n), p(1:n), nimp, timp(1:ltimp), istat)
  call legacy_after(ih, istat)
end subroutine vciadv

!> The message of the last call on IH (blank after success); IH = 0 or a dead handle: the last
!> failure that had no live integrator (a failed VCINEW, a bad IH).
subroutine vcimsg(ih, msg)
  use vci_legacy, only: legacy_message
  implicit none
  integer, intent(in) :: ih
  character(len=*), intent(out) :: msg
  msg = legacy_message(ih)
end subroutine vcimsg

!> The model checker on the model of IH at (Q, V, H): IPASS = 1 when every derivative the routine
!> supplies agrees with finite differences within TOL (<= 0: 1e-6), WORST the largest relative
!> mismatch; VCIMSG names the first failed comparison. ISTAT 0, 1 (bad IH, sizes, H <= 0) or 2.
subroutine vcichk(ih, q, v, h, tol, ipass, worst, istat)
  use vci_kinds, only: dp
  use vci_legacy, only: legacy_check, legacy_size
  implicit none
  integer, intent(in) :: ih
  real(dp), intent(in) :: q(*), v(*), h, tol
  integer, intent(out) :: ipass, istat
  real(dp), intent(out) :: worst
  integer :: n
  n = legacy_size(ih)
  call legacy_check(ih, q(1:max(n, 0)), v(1:max(n, 0)), h, tol, ipass, worst, istat)
end subroutine vcichk

!> Free integrator IH; IH becomes 0. Harmless on 0 or a deleted handle.
subroutine vcidel(ih)
  use vci_legacy, only: legacy_delete
  implicit none
  integer, intent(inout) :: ih
  call legacy_delete(ih)
end subroutine vcidel

!> One call: create, start from the pair (Q0 at T0, Q1 at T0 + H), NSTEPS steps forward with the
!> default tolerances, free. Out: the final state (T, Q, P), NIMP impacts and the first LTIMP
!> impact times in TIMP, ISTAT, and MSG (blank on success; else names the step, time and cause).
subroutine vcirun(model, n, m, ng, iopt, h, t0, q0, q1, nsteps, t, q, p, nimp, timp, ltimp, rpar, ipar, istat, msg)
  use vci_kinds, only: dp
  use vci_status, only: VCI_OK
  use vci_legacy, only: vci_legacy_model_fn, legacy_message
  implicit none
  procedure(vci_legacy_model_fn) :: model
  integer, intent(in) :: n, m, ng, iopt, nsteps, ltimp
  real(dp), intent(in) :: h, t0, q0(*), q1(*)
  real(dp), intent(inout) :: t, q(*), p(*), timp(*)
  real(dp), target, intent(inout) :: rpar(*)
  integer, target, intent(inout) :: ipar(*)
  integer, intent(out) :: nimp, istat
  character(len=*), intent(out) :: msg
  integer :: ih
  interface
    subroutine vcinew(model, n, m, ng, iopt, h, rpar, ipar, ih, istat)
      import :: dp, vci_legacy_model_fn
      procedure(vci_legacy_model_fn) :: model
      integer, intent(in) :: n, m, ng, iopt
      real(dp), intent(in) :: h
      real(dp), target, intent(inout) :: rpar(*)
      integer, target, intent(inout) :: ipar(*)
      integer, intent(out) :: ih, istat
    end subroutine vcinew
  end interface
  nimp = 0
  msg = ''
  call vcinew(model, n, m, ng, iopt, h, rpar, ipar, ih, istat)
  if (istat == VCI_OK) call vciinp(ih, t0, q0, q1, istat)
  if (istat == VCI_OK) call vciadv(ih, nsteps, 1, t, q, p, nimp, timp, ltimp, istat)
  if (istat /= VCI_OK) msg = legacy_message(ih)
  call vcidel(ih)
end subroutine vcirun

!> HDF5 output of the later VCIADV steps of IH to PATH (trailing blanks ignored): IAPP = 0 a new
!> file (replaced if it exists), IAPP = 1 continue the file (the run must go on from its last
!> state, in its direction: start it with VCIRST). The file is finished by VCICLS or VCIDEL.
!> ISTAT 0; 1 (bad IH, blank PATH, IAPP not 0 or 1); 8 (the file cannot be created or continued,
!> or no HDF5 in this build; VCIMSG says which); 10. A run that does not continue an appended
!> file is refused by its first VCIADV (ISTAT 8).
subroutine vciout(ih, path, iapp, istat)
  use vci_status, only: VCI_OK, VCI_ERR_ARGUMENT
  use vci_integrator, only: vci_integrator_t
  use vci_legacy, only: legacy_get, legacy_open_output
  implicit none
  integer, intent(in) :: ih, iapp
  character(len=*), intent(in) :: path
  integer, intent(out) :: istat
  type(vci_integrator_t), pointer :: integ
  call legacy_get(ih, 'VCIOUT', integ, istat)
  if (istat /= VCI_OK) return
  if (iapp /= 0 .and. iapp /= 1) then
    call integ%report_failure(VCI_ERR_ARGUMENT, 'VCIOUT: IAPP must be 0 (new file) or 1 (append)')
    istat = VCI_ERR_ARGUMENT; return
  end if
  call legacy_open_output(ih, path, iapp == 1, istat)
end subroutine vciout

!> Finish and close the output file of IH, if any. ISTAT 0; 1 (bad IH); 8 (it could not be finished).
subroutine vcicls(ih, istat)
  use vci_status, only: VCI_OK
  use vci_integrator, only: vci_integrator_t
  use vci_legacy, only: legacy_get, legacy_close_output
  implicit none
  integer, intent(in) :: ih
  integer, intent(out) :: istat
  type(vci_integrator_t), pointer :: integ
  call legacy_get(ih, 'VCICLS', integ, istat)
  if (istat == VCI_OK) call legacy_close_output(ih, istat)
end subroutine vcicls

!> Restart IH from the last state of the HDF5 file PATH (written by VCIOUT, vci_open_output, the
!> Fortran writer or the examples' --output): from the checkpoint the file keeps, later VCIADV calls
!> give bit for bit what the run that wrote it would have given. ISTAT 0; 1 (bad IH, blank PATH,
!> the file's N or H differ from IH's); 8 (the file cannot be read, or no HDF5 in this build);
!> 9 (the open VCIOUT file holds steps); 2, 3, 7 (the file's state refused as VCIINM would).
subroutine vcirst(ih, path, istat)
  use vci_status, only: VCI_OK
  use vci_integrator, only: vci_integrator_t
  use vci_legacy, only: legacy_get, legacy_restore
  implicit none
  integer, intent(in) :: ih
  character(len=*), intent(in) :: path
  integer, intent(out) :: istat
  type(vci_integrator_t), pointer :: integ
  call legacy_get(ih, 'VCIRST', integ, istat)
  if (istat == VCI_OK) call legacy_restore(ih, path, istat)
end subroutine vcirst
