!> One step of the (+) or (-) scheme with elastic impacts (paper, Theorem and Algorithm 1;
!> docs/DESIGN.md §1-2): a regular sub-step, and while its end leaves the admissible set, stage 1
!> (reach the first wall) and stage 2 (reflect with the energy and tangential-momentum conditions) on
!> the remaining fraction of the step, up to a bound on the number of impacts.
!>
!> This module holds the stepper's data (the scheme, Newton, the settings, the workspace) and the
!> regular step; the impact algorithm (stage 1, its bracketing, stage 2 with the energy conditions,
!> the impact record) is its submodule vci_impacts (vci_impacts.f90), Newton's start is
!> vci_predictor. The stepper knows nothing of how L_d is built (the scheme lays out the unknowns
!> and is reached through its accessors); the driver's state comes in whole (vci_state_t) and is
!> committed only when the step succeeds.
module vci_stepper
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite, ieee_value, ieee_quiet_nan
  use vci_kinds, only: dp, i8
  use vci_status
  use vci_message, only: vci_set_message, vci_int_text, vci_real_text
  use vci_newton, only: vci_newton_t, vci_newton_result_t, NEWTON_MAX_ITERATIONS, NEWTON_NO_DESCENT, &
                        NEWTON_SINGULAR, NEWTON_EVALUATION, NEWTON_NONFINITE, NEWTON_STRUCTURE, vci_large_system, &
                        NEWTON_MEMORY
  use vci_scheme, only: vci_scheme_t, KIND_SUBSTEP, KIND_STAGE1, KIND_STAGE2, KIND_IMPULSE, &
                        VCI_IMPACT_DISCRETE, VCI_IMPACT_HAMILTONIAN, VCI_IMPACT_BLENDED
  use vci_observer, only: vci_impact_t
  use vci_scheme_lobatto, only: vci_scheme_lobatto_t
  use vci_settings, only: vci_settings_t, vci_solver_stats_t, vci_too_many_impacts_cause, vci_start_beyond_cause, &
    vci_crossed_unseen_cause
  use vci_state, only: vci_state_t, vci_impact_buffer_t
  use vci_predictor, only: vci_predict_start
  use vci_explicit_step, only: vci_explicit_t
  use vci_checkpoint, only: vci_checkpoint_t
  use vci_sparse, only: vci_sparse_pattern_t
  implicit none
  private

  !> Where stage 1's first crossing is bracketed: on the chord a -> b (cheap: gap evaluations only)
  !> or on the discrete trajectory (regular sub-steps of length s tau: one Newton solve a point).
  integer, parameter :: ALONG_CHORD = 1, ALONG_TRAJECTORY = 2
  !> After the samples s = 1/8 .. 7/8: on the chord, up to CHORD_REFINEMENTS Illinois (modified
  !> regula falsi) steps until the bracket is within CHORD_WIDTH (the crossing's g is smooth in s,
  !> so it converges superlinearly: 3 to 5 gap evaluations where bisection took 20); on the
  !> trajectory, where the bracket only seeds Newton and a point costs a solve, a few bisections.
  integer, parameter :: CHORD_REFINEMENTS = 30, TRAJECTORY_BISECTIONS = 8
  !> A sub-step of a step with impacts is also sampled inside, at s = 1/(POKE_SAMPLES + 1) ..., on
  !> the discrete trajectory (a regular sub-step of length s tau each), so that a wall it passes and
  !> comes back from (a poke) is met as the other direction meets it (vci_impacts: find_poke).
  integer, parameter :: POKE_SAMPLES = 7
  !> ... and only where they are a path between its ends: two half sub-steps end within this
  !> fraction of the whole sub-step's change of q and of p (vci_impacts: samples_are_path; a
  !> stiff spring at h omega >= 10 misses by 1.0-3.6, the firm reversal scenes by at most 0.18)
  real(dp), parameter :: POKE_PATH_FRACTION = 0.25_dp
  !> ... and where no sample is beyond a wall, up to this many more at the least of a parabola fitted
  !> to the least sample and its neighbours, while that parabola comes below a wall (a dip narrower
  !> than the samples' spacing: vci_impacts, refine_samples)
  integer, parameter :: POKE_REFINEMENTS = 3
  !> The points of find_poke's path: its ends, the samples and the refinements
  integer, parameter :: POKE_PATH_POINTS = POKE_SAMPLES + 2 + POKE_REFINEMENTS
  real(dp), parameter :: CHORD_WIDTH = 1.0e-9_dp
  !> Wall gradients kept in a sub-step (grad_cache): every use follows its wall's start_gradient,
  !> so one would be correct; a few spare a second gradient for a wall examined on_wall and then
  !> in stage 1 when the sub-step ends beyond several walls.
  integer, parameter :: GRAD_SLOTS = 8

  type, public :: vci_stepper_t
    private
    class(vci_scheme_t), allocatable :: sys   !< owns the unknowns' layout; the stepper uses its accessors
    type(vci_newton_t) :: newton
    type(vci_settings_t) :: settings
    type(vci_solver_stats_t) :: stats
    integer :: n = 0, m = 0, ng = 0
    integer :: nsub = 0                             !< unknowns of a regular sub-step (the scheme's)
    logical :: fused = .true.                       !< try the scheme's fused regular-step solve first
    !> stage 2 under the hamiltonian condition without constraints: the impulse from the rates where
    !> they decide, no free motion first (issue 28; false: the free motion always, the path before)
    logical :: rates_first = .true.
    character(len=VCI_MSG_LEN) :: cause = ''       !< why the last step failed
    real(dp) :: last_residual = 0.0_dp              !< scaled residual of the last Newton solve
    integer :: last_parts = 1                       !< equal sub-steps the last step took (1: whole)
    ! Workspace, sized once by setup. Unknown vectors (the scheme's layout, up to the largest system):
    real(dp), allocatable :: x(:)             !< the unknowns Newton works on
    real(dp), allocatable :: x_stage1(:)      !< stage 1's solution for the first wall reached
    real(dp), allocatable :: x_saved(:)       !< the unknowns kept across a side computation
    real(dp), allocatable :: x_low(:), x_high(:)  !< trajectory bracket: sub-step solutions at its ends
    real(dp), allocatable :: x_full(:)        !< the whole sub-step's solution while find_poke samples inside it
    real(dp), allocatable :: jac(:, :), rhs(:), res(:), res_scale(:)  !< stage 2's linearised start
    ! Configurations and momenta (n):
    real(dp), allocatable :: q_start(:), p_start(:)  !< start of the current sub-step
    real(dp), allocatable :: q_end(:)         !< end of the regular sub-step from q_start
    real(dp), allocatable :: q_wall(:)        !< impact point (stage 1's end)
    real(dp), allocatable :: p_arrive(:)      !< momentum arriving at the wall (p-)
    real(dp), allocatable :: p_leave(:)       !< momentum leaving it (p- + mu grad g)
    real(dp), allocatable :: chord_velocity(:)  !< (q_end - q_start) / tau: stage 2's first guess
    real(dp), allocatable :: q_guess(:), q_trial(:)  !< a Newton start; an end point being examined
    ! Walls (n_gaps) and constraints (m):
    real(dp), allocatable :: gaps_start(:), gaps_end(:), gaps_trial(:)
    !> Wall gradients at q_start, computed wall by wall when first needed (O(n) a wall with the
    !> model's gap_gradient) and kept for the sub-step in GRAD_SLOTS columns, reused round robin:
    !> grad_cache(:, grad_slot(j)) is wall j's when grad_slot(j) > 0, slot_wall(k) the wall in
    !> column k (0: none). O(n) memory where a table of every wall's was n x n_gaps (issue 28).
    real(dp), allocatable :: grad_cache(:, :)
    integer, allocatable :: grad_slot(:)
    integer :: slot_wall(GRAD_SLOTS) = 0
    integer :: last_slot = 0                  !< the column written last
    real(dp), allocatable :: wall_grad(:)     !< stage 2's wall gradient at q_wall
    logical, allocatable :: wall_tried(:)     !< stage 1 solved for this wall in this sub-step
    real(dp), allocatable :: lambda_start(:), zero_lambda(:)
    real(dp), allocatable :: x_try(:)         !< stage 2's start: a point on the impulse line
    !> Several impacts in one step: stage 1's state (x, x_stage1; q_end, q_wall, p_arrive) kept while
    !> the previous impact's impulse is adjusted, to go back to when that finds no root
    real(dp), allocatable :: tie_x(:, :), tie_q(:, :)
    !> find_poke's check that the samples are a path (samples_are_path): the end (:, 1) and the
    !> momentum (:, 2) of the first half sub-step, then (:, 1) the end of the second; the end
    !> momentum of the whole sub-step (:, 3) and of the two halves (:, 4)
    real(dp), allocatable :: poke_half(:, :)
    !> find_poke's path, sorted by s: the fractions (poke_path_s), positions, gaps and solutions
    !> (sub-steps from the start) of its points, poke_npath of them
    real(dp), allocatable :: poke_path_s(:), poke_path_q(:, :), poke_path_g(:, :), poke_path_x(:, :)
    integer :: poke_npath = 0
    !> find_poke's gaps at the last sample (:, 1) and may_poke's at the step's middle (:, 2), and
    !> the multipliers the samples start from: workspace, so that a regular step allocates nothing;
    !> (:, 3 + i), i = 0 .. path_degree: the gaps at the stage polynomial's points (stage_screen)
    real(dp), allocatable :: poke_gaps(:, :), poke_lambda(:)
    !> A whole step sampled from its start, kept while the same sub-step is sampled from its end
    !> (vci_impacts: poke_seen_from_end): x (poke_keep_x); q_start, p_start, q_end, the end's
    !> momentum and the start's carried low part (poke_keep_q); gaps_end (poke_keep_g)
    real(dp), allocatable :: poke_keep_x(:, :), poke_keep_q(:, :), poke_keep_g(:)
    !> The impact condition stage 2 used (the setting, or VCI_IMPACT_HAMILTONIAN where the discrete
    !> energy condition has no solution) and, then, H(qt, p-).
    integer :: impact_condition = 0
    real(dp) :: e_fallback = 0.0_dp
    real(dp) :: e_blend_after = 0.0_dp        !< a blended impact's energy after it (e_fallback: before)
    real(dp) :: e_arrive_last = 0.0_dp        !< E_d arriving at the last impact of this step (tie_to_wall)
    logical :: has_energy = .false.           !< the model supplies H(q, p) (probed at initialisation)
    logical :: last_damped = .false.          !< (issue 27) the last Newton solve needed its line search
    real(dp), allocatable :: constraint_impulse(:)  !< nu of the Hamiltonian impact (m > 0)
    ! The step's outcome, committed to the state when the step succeeds:
    real(dp), allocatable :: q_new(:), p_new(:), lambda_new(:)
    real(dp) :: e_new = 0.0_dp
    !> An explicit composition's step (VCI_SCHEME_COMPOSITION): when allocated it takes the steps
    !> (vci_explicit_step) and `sys` serves only the queries that do not step.
    type(vci_explicit_t), allocatable :: explicit
    !> The safety net's run through equal sub-steps (split_step): its state and each part's impacts
    type(vci_state_t) :: part
    type(vci_impact_buffer_t) :: part_impacts
  contains
    procedure :: setup
    procedure :: configure
    procedure :: current_settings
    procedure :: solver_stats
    procedure :: set_solver_paths
    procedure :: factorisations
    procedure :: bordered_directions
    procedure :: failure_cause
    procedure :: use_model_derivatives
    procedure :: position_carry
    procedure :: restore_position_carry
    procedure :: factors_to_checkpoint
    procedure :: factors_from_checkpoint
    procedure :: forget_factors
    procedure :: advance
    procedure :: last_step_parts
    procedure :: use_explicit
    procedure :: explicit_steps
    procedure :: pair_momentum
    procedure :: momentum_velocity
  end type vci_stepper_t


  interface
    !> The impacts of the step whose regular sub-step ends in x (vci_impacts.f90): while the end
    !> leaves the admissible set, stage 1 and stage 2 on the rest of the step; `landed` when stage 1
    !> reached a wall exactly at the step's end (then the outcome is in q_new, p_new, lambda_new,
    !> e_new and the state's history is updated); else x holds the last sub-step from q_start of
    !> length tau.
    module subroutine resolve_impacts(self, state, dir, tau, impacts, landed, stat)
      type(vci_stepper_t), intent(inout) :: self
      type(vci_state_t), intent(inout) :: state
      integer, intent(in) :: dir
      real(dp), intent(inout) :: tau
      type(vci_impact_buffer_t), intent(inout) :: impacts
      logical, intent(out) :: landed
      integer, intent(out) :: stat
    end subroutine resolve_impacts
  end interface

  ! For the submodule vci_impacts. Public because gfortran 12 (-O2 and above) inlines a private
  ! procedure into its callers in this module and then emits no symbol for the submodule's calls.
  public :: substep, run_newton, set_cause
  ! Public so that it keeps its own symbol: callgrind counts its instructions apart from the step's
  ! (docs/bench/reversal_check.md); called only after a damped Newton solve.
  public :: confirm_by_reversal

  real(dp), parameter :: landing_fraction = 1.0e-10_dp  ! stage 1 within this of the step's end: landed on the wall

contains

  !> Take over a scheme already bound to its model (the integrator builds it) and size the workspace.
  !> The settings stay as configured. stat = VCI_ERR_MEMORY when an allocation fails.
  subroutine setup(self, scheme, stat)
    class(vci_stepper_t), intent(inout) :: self
    class(vci_scheme_t), allocatable, intent(inout) :: scheme
    integer, intent(out) :: stat
    integer :: n, m, ng, nx, ngw, nb, bw, nd
    logical :: chk
    type(vci_sparse_pattern_t), pointer :: spat
    n = scheme%n; m = scheme%m; ng = scheme%n_gaps; ngw = max(1, ng)
    self%n = n; self%m = m; self%ng = ng
    self%stats = vci_solver_stats_t()
    if (allocated(self%sys)) deallocate (self%sys)
    if (allocated(self%explicit)) deallocate (self%explicit)
    call move_alloc(scheme, self%sys)
    self%nsub = self%sys%unknowns(KIND_SUBSTEP)
    nx = max(self%sys%unknowns(KIND_STAGE1), self%sys%unknowns(KIND_STAGE2), self%sys%unknowns(KIND_IMPULSE))
    call release_workspace(self)
    ! a declared band (no debug check): Newton's matrices of vci_large_system unknowns or more are
    ! kept in band storage, so the dense ones are only the small systems' and the impulse's
    call self%sys%structure(nb, bw, chk)
    nd = nx
    if (nb > 0 .and. .not. chk) nd = min(nx, max(self%sys%unknowns(KIND_IMPULSE), vci_large_system - 1))
    call self%sys%sparse_structure(nb, spat, chk)     ! (a declared sparse pattern: likewise, smat)
    if (nb > 0 .and. .not. chk) nd = min(nx, max(self%sys%unknowns(KIND_IMPULSE), vci_large_system - 1))
    call self%newton%reserve(nx, stat, dense_max=nd)
    if (stat /= VCI_OK) return
    call self%newton%forget_factors()      ! another scheme's Jacobian is no chord matrix for this one
    ! Lobatto with constraints: one chord step before a second Jacobian (vci_newton's
    ! chord_after_newton; docs/bench/lobatto.md measures it)
    ! and no polish of a residual already within 8 ulps (polish_above)
    self%newton%chord_after_newton = .false.
    self%newton%polish_above = 0.0_dp
    select type (sys => self%sys)
    type is (vci_scheme_lobatto_t)
      self%newton%chord_after_newton = m > 0
      if (m > 0) self%newton%polish_above = 8.0_dp
    end select
    call self%configure(self%settings)
    allocate (self%x(nx), self%x_stage1(nx), self%x_saved(nx), self%x_low(nx), self%x_high(nx), self%x_full(nx), self%jac(nd, nd), &
              self%rhs(nx), self%res(nx), self%res_scale(nx), self%q_start(n), self%p_start(n), self%q_end(n), &
              self%q_wall(n), self%p_arrive(n), self%p_leave(n), self%chord_velocity(n), self%q_guess(n), &
              self%q_trial(n), self%gaps_start(ngw), self%gaps_end(ngw), self%gaps_trial(ngw), self%grad_cache(n, GRAD_SLOTS), &
              self%grad_slot(ngw), self%wall_grad(n), self%wall_tried(ngw), &
              self%lambda_start(m), self%zero_lambda(m), self%constraint_impulse(m), &
              self%x_try(nx), self%q_new(n), self%p_new(n), self%lambda_new(m), stat=stat)
    if (stat /= 0) then
      call release_workspace(self)
      stat = VCI_ERR_MEMORY; return
    end if
    self%x = 0.0_dp; self%zero_lambda = 0.0_dp
    self%grad_slot = 0; self%slot_wall = 0; self%last_slot = 0
    allocate (self%tie_x(nx, 2), self%tie_q(n, 3), self%poke_half(n, 5), self%poke_gaps(ngw, 3 + self%sys%path_degree()), &
              self%poke_lambda(m), self%poke_path_s(POKE_PATH_POINTS), self%poke_path_q(n, POKE_PATH_POINTS), &
              self%poke_path_g(ngw, POKE_PATH_POINTS), self%poke_path_x(nx, POKE_PATH_POINTS), &
              self%poke_keep_x(nx, 1), self%poke_keep_q(n, 5), self%poke_keep_g(ngw), stat=stat)
    if (stat /= 0) then
      call release_workspace(self)
      stat = VCI_ERR_MEMORY; return
    end if
  end subroutine setup

  !> Free the step's workspace, array by array: after an allocate that failed part-way some are
  !> allocated and some not.
  subroutine release_workspace(self)
    type(vci_stepper_t), intent(inout) :: self
    call free1(self%x); call free1(self%x_stage1); call free1(self%x_saved); call free1(self%x_low)
    call free1(self%x_high); call free1(self%x_full); call free2(self%jac); call free1(self%rhs); call free1(self%res)
    call free1(self%res_scale); call free1(self%q_start); call free1(self%p_start); call free1(self%q_end)
    call free1(self%q_wall); call free1(self%p_arrive); call free1(self%p_leave); call free1(self%chord_velocity)
    call free1(self%q_guess); call free1(self%q_trial); call free1(self%gaps_start); call free1(self%gaps_end)
    call free1(self%gaps_trial); call free2(self%grad_cache); call free1(self%wall_grad)
    if (allocated(self%grad_slot)) deallocate (self%grad_slot)
    if (allocated(self%wall_tried)) deallocate (self%wall_tried)
    call free1(self%lambda_start)
    call free1(self%zero_lambda); call free1(self%constraint_impulse); call free1(self%x_try)
    call free1(self%q_new); call free1(self%p_new); call free1(self%lambda_new)
    call free2(self%tie_x); call free2(self%tie_q); call free2(self%poke_half)
    call free2(self%poke_gaps); call free1(self%poke_lambda)
    call free1(self%poke_path_s); call free2(self%poke_path_q); call free2(self%poke_path_g); call free2(self%poke_path_x)
    call free2(self%poke_keep_x); call free2(self%poke_keep_q); call free1(self%poke_keep_g)
  end subroutine release_workspace

  subroutine free1(a)
    real(dp), allocatable, intent(inout) :: a(:)
    if (allocated(a)) deallocate (a)
  end subroutine free1

  subroutine free2(a)
    real(dp), allocatable, intent(inout) :: a(:, :)
    if (allocated(a)) deallocate (a)
  end subroutine free2

  !> Replace the settings (validated by the driver) and hand Newton and the scheme their part.
  subroutine configure(self, settings)
    class(vci_stepper_t), intent(inout) :: self
    type(vci_settings_t), intent(in) :: settings
    self%settings = settings
    self%newton%atol = settings%atol
    self%newton%rtol = settings%rtol
    self%newton%max_iterations = settings%max_iterations
    self%newton%bordered = settings%bordered_impacts
    self%newton%border_min = settings%border_min
    if (.not. allocated(self%sys)) return
    call self%sys%configure_impacts(settings%impact_energy, settings%rtol)
  end subroutine configure

  pure function current_settings(self) result(settings)
    class(vci_stepper_t), intent(in) :: self
    type(vci_settings_t) :: settings
    settings = self%settings
  end function current_settings

  pure function solver_stats(self) result(stats)
    class(vci_stepper_t), intent(in) :: self
    type(vci_solver_stats_t) :: stats
    stats = self%stats
  end function solver_stats

  !> Which linear-algebra paths Newton may take: the in-line LU up to small_lu_max unknowns, factor
  !> reuse from reuse_min unknowns, the scheme's fused regular-step solve when `fused` (default on;
  !> tests and benchmarks compare each path with LAPACK / full Newton / the general solve).
  subroutine set_solver_paths(self, small_lu_max, reuse_min, fused, rates_first)
    class(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: small_lu_max, reuse_min
    logical, intent(in), optional :: fused, rates_first
    self%newton%small_lu_max = small_lu_max
    self%newton%reuse_min = reuse_min
    if (present(fused)) self%fused = fused
    if (present(rates_first)) self%rates_first = rates_first
  end subroutine set_solver_paths

  !> Newton directions of impact stages solved by bordering so far.
  pure integer(i8) function bordered_directions(self)
    class(vci_stepper_t), intent(in) :: self
    bordered_directions = self%newton%bordered_directions
  end function bordered_directions

  !> LU factorisations of Newton matrices so far.
  pure integer(i8) function factorisations(self)
    class(vci_stepper_t), intent(in) :: self
    factorisations = self%newton%factorisations
  end function factorisations

  !> Why the last advance or pair_momentum failed.
  !> (Fixed length, trailing blanks: gfortran's deferred-length results are not thread-safe.)
  pure function failure_cause(self) result(cause)
    class(vci_stepper_t), intent(in) :: self
    character(len=VCI_MSG_LEN) :: cause
    cause = self%cause
  end function failure_cause

  !> Which optional derivatives the model supplies (probed by the driver): the mixed Hessian of a
  !> user's L_d (else differenced) and the gap gradients (else differenced).
  !> The compensated-summation carry of position q (for a checkpoint), and its restore.
  subroutine position_carry(self, q, lo)
    class(vci_stepper_t), intent(in) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: lo(:)
    lo = 0.0_dp
    if (allocated(self%sys)) call self%sys%position_carry(q, lo)
  end subroutine position_carry

  subroutine restore_position_carry(self, q, lo)
    class(vci_stepper_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), lo(:)
    if (allocated(self%sys)) call self%sys%restore_position_carry(q, lo)
  end subroutine restore_position_carry

  !> Newton's kept factors and the scheme's start memory into a checkpoint, so that the next steps
  !> of a restored run solve from the same factors and start as the uninterrupted one (docs/DESIGN.md,
  !> "Restart bit for bit"). stat: VCI_ERR_MEMORY when either cannot be copied (a checkpoint without
  !> them restarts correct but not bit for bit, so it is no checkpoint: the caller drops it), and
  !> `what` names the copy; cp's factors and start may then be partly allocated.
  subroutine factors_to_checkpoint(self, cp, stat, what)
    class(vci_stepper_t), intent(in) :: self
    type(vci_checkpoint_t), intent(inout) :: cp
    integer, intent(out) :: stat
    character(len=*), intent(out) :: what
    what = ''
    call self%newton%kept_factors(cp%factors_n, cp%factors_key, cp%factors_rw, cp%factors_lu, cp%factors_pivots, stat)
    if (stat /= VCI_OK) then
      what = 'Newton''s kept factors'; stat = VCI_ERR_MEMORY; return
    end if
    ! and the scheme's start memory (Lobatto with constraints: its last step's polynomials)
    if (allocated(cp%start)) deallocate (cp%start)
    if (.not. allocated(self%sys)) return
    call self%sys%start_memory(cp%start, stat)
    if (stat /= VCI_OK) then
      what = 'the scheme''s start memory'; stat = VCI_ERR_MEMORY; return
    end if
    if (size(cp%start) == 0) deallocate (cp%start)
  end subroutine factors_to_checkpoint

  !> The checkpoint's factors (or none) become Newton's kept ones, its start memory (or none) the scheme's.
  subroutine factors_from_checkpoint(self, cp)
    class(vci_stepper_t), intent(inout) :: self
    type(vci_checkpoint_t), intent(in) :: cp
    call self%newton%forget_factors()
    if (cp%factors_n > 0 .and. allocated(cp%factors_rw) .and. allocated(cp%factors_lu) .and. &
        allocated(cp%factors_pivots)) &
      call self%newton%keep_factors(cp%factors_n, cp%factors_key, cp%factors_rw, cp%factors_lu, cp%factors_pivots)
    if (allocated(self%sys)) then
      if (allocated(cp%start)) then
        call self%sys%restore_start_memory(cp%start)
      else
        call self%sys%restore_start_memory([real(dp) ::])
      end if
    end if
  end subroutine factors_from_checkpoint

  !> A new run: no factors or start memory of an earlier one (a re-initialised integrator runs as a fresh one).
  subroutine forget_factors(self)
    class(vci_stepper_t), intent(inout) :: self
    call self%newton%forget_factors()
    if (allocated(self%sys)) call self%sys%restore_start_memory([real(dp) ::])   ! nor its start memory
  end subroutine forget_factors

  subroutine use_model_derivatives(self, mixed_hessian, gap_gradients, constraint_jacobian, energy, gap_gradient, &
                                   fused)
    class(vci_stepper_t), intent(inout) :: self
    logical, intent(in), optional :: mixed_hessian, gap_gradients, constraint_jacobian
    logical, intent(in), optional :: energy   !< the model has H(q, p) (the discrete condition's fallback)
    logical, intent(in), optional :: gap_gradient   !< the model has one wall's gradient (gap_gradient)
    logical, intent(in), optional :: fused    !< the model has the fused L_d callback (vci_model_t%ld_fused)
    if (present(energy)) self%has_energy = energy
    if (present(gap_gradient)) self%sys%has_gap_gradient = gap_gradient
    call self%sys%use_derivatives(mixed_hessian, gap_gradients, constraint_jacobian, fused)
  end subroutine use_model_derivatives

  !> One step of length state%h in direction dir (+1/-1) from the state, through its impacts.
  !> On success the state holds the new step (q, p, lambda, E_d, index, history) and
  !> impacts%records(1:impacts%count) the step's impacts (the records grow on demand, up to
  !> settings%max_impacts_per_step of them, which may be huge). On failure q, p, lambda, the index
  !> and E_d stay; the arriving energy is marked unknown (arriving_direction = 0).
  subroutine advance(self, state, dir, impacts, stat)
    class(vci_stepper_t), intent(inout) :: self
    type(vci_state_t), intent(inout) :: state
    integer, intent(in) :: dir
    type(vci_impact_buffer_t), intent(inout) :: impacts
    integer, intent(out) :: stat
    integer :: i
    integer(i8) :: fallbacks, irreversible
    real(dp) :: arriving
    if (state%arriving_direction /= dir) state%arriving_energy = ieee_value(1.0_dp, ieee_quiet_nan)
    arriving = state%arriving_energy     ! a failed attempt may have changed it
    self%last_parts = 1
    fallbacks = self%stats%energy_fallbacks; irreversible = self%stats%irreversible_impacts
    call take_step(self, state, dir, impacts, stat)
    ! energy_fallbacks counts the impacts of the steps taken: a failed attempt's impacts are
    ! discarded (a count of them made the two directions of a reversal differ where only one split)
    if (stat /= VCI_OK) self%stats%energy_fallbacks = fallbacks
    if (stat /= VCI_OK) self%stats%irreversible_impacts = irreversible
    if (stat /= VCI_OK .and. self%settings%max_step_splits >= 2) then
      if (stat == VCI_ERR_NEWTON .or. stat == VCI_ERR_IMPACT .or. stat == VCI_ERR_TOO_MANY_IMPACTS) &
        call split_step(self, state, dir, arriving, impacts, stat)
    end if
    if (stat /= VCI_OK) then
      state%arriving_direction = 0
      return
    end if
    state%arriving_direction = dir
    do i = 1, impacts%count
      impacts%records(i)%step = state%k
    end do
    state%q(:) = self%q_new; state%p(:) = self%p_new     ! ((:): no reallocation check per step)
    if (self%m > 0) state%lambda(:) = self%lambda_new
    state%step_energy = self%e_new
    state%k = state%k + dir
  end subroutine advance

  !> The safety net (docs/DESIGN.md §2, "Steps that cannot be solved"): the step that just failed
  !> (its status in stat, its cause in self%cause) once more as 2, 4, ... equal sub-steps of length
  !> h / parts, each a step of the same scheme from the end of the one before (so the map stays
  !> symplectic and momentum-preserving), up to settings%max_step_splits of them; the last part ends
  !> exactly at the grid time. Each part may have up to max_impacts_per_step impacts. On success the
  !> outcome is in q_new, p_new, lambda_new, e_new (E_d of the last part), impacts holds the parts'
  !> impacts (alpha as a fraction of the whole step), the statistics count the step. When every
  !> split fails: the first attempt's status, its cause and what the finest split met.
  !> Equal sub-steps the last step advance took (1: whole; > 1: the safety net split it).
  pure integer function last_step_parts(self)
    class(vci_stepper_t), intent(in) :: self
    last_step_parts = self%last_parts
  end function last_step_parts

  subroutine split_step(self, state, dir, arriving, impacts, stat)
    type(vci_stepper_t), intent(inout) :: self
    type(vci_state_t), intent(inout) :: state
    integer, intent(in) :: dir
    real(dp), intent(in) :: arriving
    type(vci_impact_buffer_t), intent(inout) :: impacts
    integer, intent(inout) :: stat
    integer :: first_stat, parts, i, k, st, tried
    integer(i8) :: fallbacks, irreversible
    character(len=VCI_MSG_LEN) :: first_cause
    character(len=2 * VCI_MSG_LEN) :: combined
    character(len=16) :: last_parts
    first_stat = stat; first_cause = self%cause
    fallbacks = self%stats%energy_fallbacks      ! (a failed split's impacts are discarded too)
    irreversible = self%stats%irreversible_impacts
    st = VCI_OK
    if (.not. allocated(self%part_impacts%records)) then
      call self%part_impacts%reserve(min(self%settings%max_impacts_per_step, 16), self%n, st)
      if (st /= VCI_OK) return
    end if
    parts = 2; tried = 0
    do while (parts <= self%settings%max_step_splits)
      tried = parts
      self%part = state
      self%part%arriving_energy = arriving
      self%part%h = state%h / real(parts, dp)
      self%part%t0 = state%time(); self%part%k = 0_i8      ! part i ends at t0 + i (h / parts)
      call self%part%forget_history()                   ! the history is of steps of another length
      impacts%count = 0
      do i = 1, parts
        if (self%part%arriving_direction /= dir) self%part%arriving_energy = ieee_value(1.0_dp, ieee_quiet_nan)
        call take_step(self, self%part, dir, self%part_impacts, st)
        if (st /= VCI_OK) exit
        if (self%part_impacts%count > 0) then
          call impacts%reserve(impacts%count + self%part_impacts%count, self%n, st)
          if (st /= VCI_OK) then
            self%cause = 'cannot allocate the records of the impacts of a split step'; exit
          end if
          do k = 1, self%part_impacts%count
            impacts%count = impacts%count + 1
            impacts%records(impacts%count) = self%part_impacts%records(k)
            impacts%records(impacts%count)%alpha = (real(i - 1, dp) + self%part_impacts%records(k)%alpha) / real(parts, dp)
          end do
        end if
        self%part%q(:) = self%q_new; self%part%p(:) = self%p_new
        if (self%m > 0) self%part%lambda(:) = self%lambda_new
        self%part%step_energy = self%e_new
        self%part%k = self%part%k + dir
        self%part%arriving_direction = dir
      end do
      if (st == VCI_OK) then
        ! the step as a whole: its velocity starts the next step's predictor afresh; with interior
        ! stages the last part's (after an impact its polynomial's end velocity, not a chord bent by
        ! the reflection)
        state%velocity = real(dir, dp) * (self%q_new - state%q) / state%h
        if (self%sys%needs_pair_solve()) state%velocity = self%part%velocity
        state%predictor_depth = 0
        state%arriving_energy = self%part%arriving_energy
        self%stats%split_steps = self%stats%split_steps + 1
        self%stats%largest_split = max(self%stats%largest_split, int(parts, i8))
        self%last_parts = parts
        stat = VCI_OK
        return
      end if
      self%stats%energy_fallbacks = fallbacks
      self%stats%irreversible_impacts = irreversible
      if (st == VCI_ERR_MEMORY .or. st == VCI_ERR_CALLBACK .or. st == VCI_ERR_NONFINITE) exit
      parts = 2 * parts
    end do
    impacts%count = 0
    stat = first_stat
    if (tried == 0) then
      self%cause = first_cause; return
    end if
    write (last_parts, '(i0)') tried
    ! the driver puts the step and time before the cause in a message of VCI_MSG_LEN characters
    combined = trim(first_cause)//'; retried as 2 to '//trim(last_parts)//' equal sub-steps (safety net): '// &
               trim(self%cause)
    self%cause = combined(1:VCI_MSG_LEN - 120)
  end subroutine split_step

  !> The step itself: the regular sub-step from the predictor's start, the impacts, the momentum
  !> and E_d of the last sub-step. The outcome goes to q_new, p_new, lambda_new, e_new; the
  !> history (velocity, predictor depth, arriving energy) is updated in the state.
  subroutine take_step(self, state, dir, impacts, stat)
    type(vci_stepper_t), intent(inout) :: self
    type(vci_state_t), intent(inout) :: state
    integer, intent(in) :: dir
    type(vci_impact_buffer_t), intent(inout) :: impacts
    integer, intent(out) :: stat
    real(dp) :: tau
    logical :: landed, known

    if (allocated(self%explicit)) then
      call explicit_take_step(self, state, dir, impacts, stat); return
    end if
    call self%sys%set_direction(dir)
    impacts%count = 0
    if (self%cause(1:1) /= ' ') self%cause = ''   ! (causes start with a word; blanking all of it costs per step)
    self%q_start(:) = state%q; self%p_start(:) = state%p; tau = state%h
    ! the regular step, from the extrapolated guess
    if (state%predictor_depth * dir < 0) state%predictor_depth = 0    ! the history runs the other way
    call vci_predict_start(self%sys, state, dir, abs(state%predictor_depth), self%x, self%q_guess, self%lambda_start)
    call substep(self, self%q_start, self%p_start, tau, stat)
    if (stat == VCI_ERR_NEWTON .and. .not. self%sys%unrecoverable .and. self%settings%poke_samples) then
      ! once more from rest (q_start at both ends) before the safety net splits the step: the
      ! split's equal sub-steps are not the inverse of the whole step the other direction took
      ! (firm reversal seed 228, Lobatto s = 2, quartic L: 1e-4 off its start). Only with the poke
      ! samples, the setting for runs that must reverse: from rest, the walled pendulum's midpoint
      ! ladder at h = 1 took another root (error 5.1 against 0.56 with its steps split)
      call self%sys%put_endpoint(self%x, self%q_start, self%q_start)
      call self%sys%put_multipliers(self%x, state%lambda)
      call substep(self, self%q_start, self%p_start, tau, stat)
    end if
    if (stat /= VCI_OK) return
    ! a root reached by a damped iteration left the predictor's convergence region: it must be the
    ! motion's (docs/DESIGN.md §6, "The regular step's root checked by its reversal")
    if (self%last_damped .and. self%sys%needs_pair_solve()) then
      call confirm_by_reversal(self, dir, tau, stat)
      if (stat /= VCI_OK) return
    end if

    if (self%ng > 0) then
      call resolve_impacts(self, state, dir, tau, impacts, landed, stat)
      if (stat /= VCI_OK .or. landed) return
    end if

    call self%sys%get_endpoint(self%x, self%q_new)
    call self%sys%get_multipliers(self%x, self%lambda_new)
    ! x balances p_start, or after an impact p- + mu grad g (with the Hamiltonian condition the
    ! constraint impulse is in x's multipliers, not in that momentum)
    if (impacts%count > 0) self%p_leave = self%p_arrive + self%sys%get_extra(self%x, KIND_STAGE2) * self%sys%grad
    if (impacts%count == 0) then
      call self%sys%momentum_out(self%x, self%q_start, tau, self%p_new, stat, self%p_start)
    else
      call self%sys%impact_momentum(self%x, self%q_start, tau, self%p_new, stat, self%p_leave)
    end if
    if (stat == VCI_OK) call self%sys%energy_out(self%x, self%q_start, tau, self%e_new, stat)
    if (stat /= VCI_OK) then
      call set_cause(self, 'momentum of the new state'); return
    end if
    if (impacts%count == 0) then
      ! a regular step: it extends the predictor's history
      state%velocity_before = state%velocity
      if (self%m > 0) then
        state%lambda_before2 = state%lambda_before; state%lambda_before = state%lambda
      end if
      state%predictor_depth = dir * min(abs(state%predictor_depth) + 1, 3)
    else
      state%predictor_depth = 0              ! an impact breaks the smooth history
    end if
    state%velocity = real(dir, dp) * (self%q_new - self%q_start) / tau
    ! after an impact, the velocity at the end of the leaving sub-step, where the scheme has a
    ! polynomial through it (issue 27): the chord of a step with a reflection in it is O(1) off and
    ! started the next regular step far enough away for Newton to reach a spurious root
    if (impacts%count > 0) call self%sys%end_velocity(self%x, tau, state%velocity, known)
    state%arriving_energy = self%e_new
  end subroutine take_step

  !> Is the regular step's root (in x, from q_start, p_start over tau) the motion's? (issue 27) A
  !> symmetric scheme's step from (q1, p1) run backwards has q_start as a root whatever root q1 is;
  !> on the motion's branch (the one continued from tau -> 0) it is the root Newton reaches from the
  !> reversed step's free-flight start q1 - dir tau v1 (v1 the root's own end velocity), as the
  !> forward step reaches q1 from its start. A spurious root's reversed step lands on its own
  !> motion instead (Kepler, lobatto s = 2, h = 0.8, from rest: at (1.93, 3.47), not at the
  !> pericentre (0.5, 0)). A reversed step that ends more than 1e-6 of the step's span from q_start
  !> fails the step with VCI_ERR_NEWTON (the safety net splits it); one that does not converge
  !> decides nothing. Called only after a damped Newton solve; x and the posed sub-step are restored.
  subroutine confirm_by_reversal(self, dir, tau, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: dir
    real(dp), intent(in) :: tau
    integer, intent(out) :: stat
    integer :: nx, st
    real(dp) :: span, off
    logical :: known
    nx = self%nsub
    self%x_saved(1:nx) = self%x(1:nx)
    ! (workspace: q_end, p_arrive, q_guess and q_trial are set afresh by resolve_impacts before use)
    call self%sys%get_endpoint(self%x, self%q_end)
    call self%sys%momentum_out(self%x, self%q_start, tau, self%p_arrive, stat, self%p_start)
    if (stat /= VCI_OK) then
      call set_cause(self, 'momentum of the regular step'); return
    end if
    call self%sys%end_velocity(self%x, tau, self%q_guess, known)
    if (.not. known) return
    span = maxval(abs(self%q_end - self%q_start))
    self%q_guess = self%q_end - real(dir, dp) * tau * self%q_guess
    call self%sys%set_direction(-dir)
    call self%sys%put_endpoint(self%x, self%q_end, self%q_guess)
    call substep(self, self%q_end, self%p_arrive, tau, st)
    off = 0.0_dp
    if (st == VCI_OK) then
      call self%sys%get_endpoint(self%x, self%q_trial)
      off = maxval(abs(self%q_trial - self%q_start))
    end if
    call self%sys%set_direction(dir)
    self%x(1:nx) = self%x_saved(1:nx)
    self%cause = ''
    call self%sys%pose_substep(self%q_start, self%p_start, tau, stat)
    if (stat /= VCI_OK) then
      call set_cause(self, 'constraint forms'); return
    end if
    if (off > 1.0e-6_dp * span) then
      stat = VCI_ERR_NEWTON
      call vci_set_message(self%cause, 'regular step: Newton reached a spurious root (the step reversed from it, '// &
        'started from its end velocity, ends '//trim(vci_real_text(off, '(es9.2)'))//' from the start instead of '// &
        'returning there); a shorter step reaches the motion''s')
    end if
  end subroutine confirm_by_reversal

  !> Take the steps with an explicit composition (after setup, which drops any earlier one).
  subroutine use_explicit(self, explicit)
    class(vci_stepper_t), intent(inout) :: self
    type(vci_explicit_t), allocatable, intent(inout) :: explicit
    call move_alloc(explicit, self%explicit)
  end subroutine use_explicit

  !> The explicit composition's step (vci_explicit_step): no Newton, no predictor history.
  subroutine explicit_take_step(self, state, dir, impacts, stat)
    type(vci_stepper_t), intent(inout) :: self
    type(vci_state_t), intent(inout) :: state
    integer, intent(in) :: dir
    type(vci_impact_buffer_t), intent(inout) :: impacts
    integer, intent(out) :: stat
    if (self%cause(1:1) /= ' ') self%cause = ''
    call explicit_condition(self)
    call self%explicit%advance(state%q, state%p, state%h, dir, state%time(), self%settings%max_impacts_per_step, &
                               impacts, self%q_new, self%p_new, self%e_new, self%cause, stat)
    call explicit_condition(self)
    if (stat /= VCI_OK) return
    state%predictor_depth = 0
    state%velocity = real(dir, dp) * (self%q_new - state%q) / state%h
    state%arriving_energy = self%e_new
  end subroutine explicit_take_step

  !> The explicit step follows the impact-energy setting once set_impact_energy chose it, else it
  !> keeps the hamiltonian condition (the default `discrete` is the implicit schemes'; for the
  !> compositions it costs more and its energy error is larger: docs/SCHEMES.md); its grazes
  !> under the discrete condition (mirror kept) are counted with the energy fallbacks. Its dip screen follows set_poke_samples.
  subroutine explicit_condition(self)
    type(vci_stepper_t), intent(inout) :: self
    self%explicit%condition = merge(self%settings%impact_energy, VCI_IMPACT_HAMILTONIAN, &
                                    self%settings%impact_energy_chosen)
    self%explicit%screen_dips = self%settings%poke_samples
    self%stats%energy_fallbacks = self%stats%energy_fallbacks + self%explicit%fallbacks
    self%explicit%fallbacks = 0
    self%stats%irreversible_impacts = self%stats%irreversible_impacts + self%explicit%irreversible
    self%explicit%irreversible = 0
  end subroutine explicit_condition

  !> Regular sub-step of length tau from (a, pa); x holds the initial guess and returns the solution.
  subroutine substep(self, a, pa, tau, stat)
    type(vci_stepper_t), intent(inout) :: self
    real(dp), intent(in) :: a(:), pa(:), tau
    integer, intent(out) :: stat
    integer :: nx
    type(vci_newton_result_t) :: res
    logical :: done
    nx = self%nsub
    call self%sys%pose_substep(a, pa, tau, stat)
    if (stat /= VCI_OK) then
      call set_cause(self, 'constraint forms'); return
    end if
    self%last_damped = .false.
    if (self%fused) then
      ! small analytic systems: the fused solve; anything unusual there is redone on the general
      ! path, except a callback's unrecoverable failure, which ends the step at once (the flag is
      ! reset, not the message buffer: blanking that every step costs; a failure writes it anew)
      self%sys%unrecoverable = .false.
      call self%sys%fused_substep(self%newton, self%x(1:nx), res, done)
      if (done) then
        self%stats%fused_solves = self%stats%fused_solves + 1
        call count_solve(self, res)
        stat = VCI_OK
        return
      end if
      if (self%sys%unrecoverable) then
        stat = VCI_ERR_CALLBACK
        self%cause = 'regular step: callback '//trim(self%sys%failed_callback)//' reported failure'// &
                     trim(stat_text(self%sys%failed_stat))
        return
      end if
    end if
    call run_newton(self, nx, 'regular step', stat)
  end subroutine substep

  !> The free flight's velocity at a state given by (q, p) (init_from_momentum), for the first step's
  !> Newton start (issue 27): the end velocity of a regular sub-step of 1e-3 h from (q, p), solved
  !> from rest (its start is O(1e-3 h |v|) off, so Newton converges as on any short sub-step). Only
  !> schemes with interior stages have such a velocity (end_velocity); elsewhere, and when that
  !> sub-step fails, the velocity stays 0 and the first step starts from q as before.
  subroutine momentum_velocity(self, state)
    class(vci_stepper_t), intent(inout) :: self
    type(vci_state_t), intent(inout) :: state
    real(dp), parameter :: eps_frac = 1.0e-3_dp
    integer :: stat
    logical :: known
    state%velocity = 0.0_dp
    if (allocated(self%explicit) .or. .not. self%sys%needs_pair_solve()) return
    call self%sys%set_direction(1)
    call self%sys%put_endpoint(self%x, state%q, state%q)
    call self%sys%put_multipliers(self%x, state%lambda)
    call substep(self, state%q, state%p, eps_frac * state%h, stat)
    if (stat == VCI_OK) then
      call self%sys%end_velocity(self%x, eps_frac * state%h, self%q_guess, known)
      if (known) state%velocity = self%q_guess
    end if
    self%cause = ''
  end subroutine momentum_velocity

  !> The momentum p1 at q1 and the discrete energy of the segment from q0 to q1 of length h, forward
  !> (the paper's initial pair). Schemes with interior stages solve for them first (KIND_PAIR).
  subroutine pair_momentum(self, q0, q1, h, p1, e, stat)
    class(vci_stepper_t), intent(inout) :: self
    real(dp), intent(in) :: q0(:), q1(:), h
    real(dp), intent(out) :: p1(:), e
    integer, intent(out) :: stat
    call self%sys%set_direction(1)
    self%cause = ''
    call self%sys%put_endpoint(self%x, q0, q1)
    call self%sys%put_multipliers(self%x, self%zero_lambda)
    if (self%sys%needs_pair_solve()) then
      call self%sys%pose_pair(q0, q1, h)
      call run_newton(self, self%nsub, 'interior stages of the initial pair', stat)
      if (stat /= VCI_OK) return
    end if
    call self%sys%momentum_out(self%x, q0, h, p1, stat)
    if (stat == VCI_OK) call self%sys%energy_out(self%x, q0, h, e, stat)
    if (stat == VCI_OK) return
    if (self%sys%needs_pair_solve()) then
      call set_cause(self, 'momentum of the initial pair')
    else
      self%cause = 'callback '//trim(self%sys%failed_callback)//' failed or returned NaN/Inf at the initial pair'
    end if
  end subroutine pair_momentum

  subroutine run_newton(self, nx, what, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: nx
    character(len=*), intent(in) :: what
    integer, intent(out) :: stat
    type(vci_newton_result_t) :: res
    call self%sys%clear_failure()
    call self%sys%forget_jacobian()
    call self%newton%solve(self%sys, self%x(1:nx), res)
    call count_solve(self, res)
    self%last_damped = res%damped
    stat = res%status
    if (stat == VCI_OK) return
    select case (res%reason)
    case (NEWTON_MAX_ITERATIONS)
      call vci_set_message(self%cause, what//': Newton did not converge in '//trim(vci_int_text(res%iterations))// &
        ' iterations (scaled residual '//trim(vci_real_text(res%scaled_residual, '(es9.2)'))//')')
      call explain_newton(self, nx)
    case (NEWTON_NO_DESCENT)
      call vci_set_message(self%cause, what//': Newton line search found no decrease (scaled residual '// &
        trim(vci_real_text(res%scaled_residual, '(es9.2)'))//')')
      call explain_newton(self, nx)
    case (NEWTON_SINGULAR)
      self%cause = what//': Newton matrix singular and least-squares solve failed'
      call explain_newton(self, nx)
    case (NEWTON_NONFINITE)
      self%cause = what//': residual or Newton matrix not finite (callback values overflow)'
    case (NEWTON_MEMORY)
      call vci_set_message(self%cause, what//': out of memory for a dense Newton matrix of '// &
        trim(vci_int_text(nx))//' unknowns')
    case (NEWTON_STRUCTURE)      ! (the debug check of a declared Hessian bandwidth or pattern)
      call vci_set_message(self%cause, what//': the Newton matrix has a nonzero at ('//trim(vci_int_text(res%bad_row))// &
        ', '//trim(vci_int_text(res%bad_col))//') outside the Hessian bandwidth the model declared, or its sparse pattern')
    case (NEWTON_EVALUATION)
      if (stat == VCI_ERR_NONFINITE) then
        self%cause = what//': callback '//trim(self%sys%failed_callback)//' returned NaN or Inf'
      else
        self%cause = what//': callback '//trim(self%sys%failed_callback)//' reported failure'// &
                     trim(stat_text(self%sys%failed_stat))
      end if
    end select
  end subroutine run_newton

  !> Append to a convergence failure's cause which equation stayed unsolved and what usually causes
  !> that (a user reading "no decrease" alone cannot tell a too-large step from a wrong derivative).
  subroutine explain_newton(self, nx)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: nx
    integer :: i
    i = self%newton%worst_row(nx)
    if (i < 1) return
    self%cause = trim(self%cause)//'; unsolved: '//trim(self%sys%row_name(i))// &
      '. Likely causes: a step too large for the motion (lower h), or derivatives inconsistent with '// &
      'each other or with L (run vci_check_model / --check-model)'
  end subroutine explain_newton

  !> A finished solve in the statistics (either path).
  subroutine count_solve(self, res)
    type(vci_stepper_t), intent(inout) :: self
    type(vci_newton_result_t), intent(in) :: res
    self%stats%newton_solves = self%stats%newton_solves + 1
    self%stats%newton_iterations = self%stats%newton_iterations + res%iterations
    if (res%used_fallback) self%stats%fallbacks = self%stats%fallbacks + 1
    self%last_residual = res%scaled_residual
  end subroutine count_solve


  subroutine set_cause(self, what)
    type(vci_stepper_t), intent(inout) :: self
    character(len=*), intent(in) :: what
    if (len_trim(self%sys%failed_callback) > 0 .and. self%sys%failed_stat /= 0) then
      self%cause = what//': callback '//trim(self%sys%failed_callback)//' reported failure'// &
                   trim(stat_text(self%sys%failed_stat))
    else if (len_trim(self%sys%failed_callback) > 0) then
      self%cause = what//': callback '//trim(self%sys%failed_callback)//' failed or returned NaN/Inf'
    else
      self%cause = what//' failed'
    end if
  end subroutine set_cause

  !> " (stat = k, recoverable)" or " (stat = k, unrecoverable)": the callback's own code. Fixed
  !> length: gfortran's deferred-length function results are not thread-safe.
  function stat_text(stat) result(text)
    integer, intent(in) :: stat
    character(len=48) :: text
    character(len=16) :: k
    text = ''
    if (stat == 0) return
    write (k, '(i0)') stat
    text = ' (stat = '//trim(k)//trim(merge(', recoverable  ', ', unrecoverable', stat > 0))//')'
  end function stat_text

  ! ---- explicit compositions: a run of steps without per-step bookkeeping (issue 32) ----

  !> Up to nsteps steps of the explicit composition in direction dir, committed to the state
  !> (vci_explicit_step's run: the same bits as advance, without H and the velocity, which the
  !> run's last step, taken by advance, sets). done = 0 when the steps are not explicit; the run
  !> stops before a failing step, which advance then retakes and reports.
  subroutine explicit_steps(self, state, nsteps, dir, impacts, done, found)
    class(vci_stepper_t), intent(inout) :: self
    type(vci_state_t), intent(inout) :: state
    integer(i8), intent(in) :: nsteps
    integer, intent(in) :: dir
    type(vci_impact_buffer_t), intent(inout) :: impacts
    integer(i8), intent(out) :: done, found
    done = 0; found = 0
    if (.not. allocated(self%explicit) .or. nsteps < 1) return
    call explicit_condition(self)
    call self%explicit%run(state, nsteps, dir, self%settings%max_impacts_per_step, impacts, done, found)
    call explicit_condition(self)
  end subroutine explicit_steps

end module vci_stepper
