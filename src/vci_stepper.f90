!> One step of the (+) or (-) scheme with elastic impacts (paper, Theorem and Algorithm 1;
!> DESIGN.md §1): a regular sub-step, and while its end leaves the admissible set, stage 1 (reach
!> the first wall) and stage 2 (reflect with the energy and tangential-momentum conditions) on the
!> remaining fraction of the step, up to a bound on the number of impacts.
module vci_stepper
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use vci_kinds, only: dp, i8
  use vci_status
  use vci_newton, only: vci_newton_t, vci_newton_result_t, NEWTON_MAX_ITERATIONS, NEWTON_NO_DESCENT, &
                        NEWTON_SINGULAR, NEWTON_EVALUATION
  use vci_scheme, only: vci_scheme_t, KIND_SUBSTEP, KIND_WALL, KIND_REFLECT, KIND_IMPULSE, KIND_PAIR, &
                        VCI_IMPACT_DISCRETE, VCI_IMPACT_HAMILTONIAN
  use vci_observer, only: vci_impact_t
  implicit none
  private

  !> Solver and impact settings.
  type, public :: vci_settings_t
    real(dp) :: atol = 0.0_dp            !< absolute floor of Newton's per-row tolerance
    real(dp) :: rtol = 1.0e-12_dp        !< Newton tolerance relative to the size of each row's terms
    integer :: max_iterations = 30       !< Newton iteration cap per solve
    integer :: max_impacts_per_step = 16 !< beyond this: VCI_ERR_TOO_MANY_IMPACTS (contact, chatter)
    integer :: impact_energy = VCI_IMPACT_DISCRETE
  end type vci_settings_t

  !> Cumulative solver statistics.
  type, public :: vci_solver_stats_t
    integer(i8) :: newton_solves = 0, newton_iterations = 0, fallbacks = 0
  end type vci_solver_stats_t

  type, public :: vci_stepper_t
    class(vci_scheme_t), allocatable :: sys   !< owns the unknowns' layout; the stepper uses its accessors
    type(vci_newton_t) :: newton
    type(vci_settings_t) :: settings
    type(vci_solver_stats_t) :: stats
    integer :: n = 0, m = 0, ng = 0
    integer :: nsub = 0                             !< unknowns of a regular sub-step (the scheme's)
    type(vci_impact_t), allocatable :: impacts(:)  !< impacts of the last step
    integer :: n_impacts = 0
    character(len=VCI_MSG_LEN) :: cause = ''       !< why the last step failed
    real(dp) :: last_residual = 0.0_dp              !< scaled residual of the last Newton solve
    real(dp), allocatable, private :: x(:), a(:), pa(:), b(:), qt(:), pminus(:), gb(:), ga(:), dga(:, :)
    real(dp), allocatable, private :: best_x(:), jac(:, :), rhs(:), r(:), sc(:), vin(:), pimp(:), nu(:)
    real(dp), allocatable, private :: qs(:), gw(:), xlo(:), xhi(:), lam0(:), bt(:), zm(:)
  contains
    procedure :: setup
    procedure :: reserve_impacts
    procedure :: advance
    procedure :: arriving_energy
    procedure :: pair_momentum
  end type vci_stepper_t

  real(dp), parameter :: landing_fraction = 1.0e-10_dp  ! stage 1 within this of the step's end: landed on the wall

contains

  !> Take over a scheme already bound to its model (the integrator builds it) and size the workspace.
  subroutine setup(self, scheme, settings)
    class(vci_stepper_t), intent(inout) :: self
    class(vci_scheme_t), allocatable, intent(inout) :: scheme
    type(vci_settings_t), intent(in) :: settings
    integer :: n, m, ng, nx
    n = scheme%n; m = scheme%m; ng = scheme%n_gaps
    self%n = n; self%m = m; self%ng = ng
    self%settings = settings
    self%stats = vci_solver_stats_t()
    if (allocated(self%sys)) deallocate (self%sys)
    call move_alloc(scheme, self%sys)
    self%nsub = self%sys%unknowns(KIND_SUBSTEP)
    nx = max(self%sys%unknowns(KIND_WALL), self%sys%unknowns(KIND_REFLECT), self%sys%unknowns(KIND_IMPULSE))
    call self%newton%reserve(nx)
    call apply_settings(self)
    if (allocated(self%x)) deallocate (self%x, self%a, self%pa, self%b, self%qt, self%pminus, self%gb, &
                                       self%ga, self%dga, self%best_x, self%jac, self%rhs, self%r, self%sc, &
                                       self%vin, self%pimp, self%nu, self%qs, self%gw, &
                                       self%xlo, self%xhi, self%lam0, self%bt, self%zm)
    allocate (self%x(nx), self%a(n), self%pa(n), self%b(n), self%qt(n), self%pminus(n), &
              self%gb(max(1, ng)), self%ga(max(1, ng)), self%dga(n, max(1, ng)), self%best_x(nx), &
              self%jac(nx, nx), self%rhs(nx), self%r(nx), self%sc(nx), self%vin(n), self%pimp(n), self%nu(m), &
              self%qs(n), self%gw(max(1, ng)), self%xlo(nx), self%xhi(nx), self%lam0(m), self%bt(n), self%zm(m))
    self%x = 0.0_dp; self%zm = 0.0_dp
    call self%reserve_impacts(settings%max_impacts_per_step)
  end subroutine setup

  !> Room for the impact records of one step (the bound on impacts per step).
  subroutine reserve_impacts(self, max_impacts)
    class(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: max_impacts
    integer :: i
    if (allocated(self%impacts)) deallocate (self%impacts)
    allocate (self%impacts(max(1, max_impacts)))
    do i = 1, size(self%impacts)
      allocate (self%impacts(i)%q(self%n), self%impacts(i)%p_before(self%n), self%impacts(i)%p_after(self%n), &
                self%impacts(i)%grad_g(self%n))
    end do
    self%n_impacts = 0
  end subroutine reserve_impacts

  subroutine apply_settings(self)
    type(vci_stepper_t), intent(inout) :: self
    self%newton%atol = self%settings%atol
    self%newton%rtol = self%settings%rtol
    self%newton%max_iterations = self%settings%max_iterations
    self%sys%impact_energy = self%settings%impact_energy
    self%sys%rtol = self%settings%rtol
  end subroutine apply_settings

  !> Advance from (q, p) by one step of length h in direction dir (+1/-1).
  !> vel: forward-time velocity estimate (initial guesses; updated). e_arrive: E_d of the sub-step
  !> that arrived at q in this direction (needed only when q is on a wall and the motion goes into it).
  !> On success qn, pn, lambdan hold the new state and e_step the E_d of the step's last sub-step.
  subroutine advance(self, dir, h, t, q, p, lambda, vel, e_arrive, qn, pn, lambdan, e_step, stat)
    class(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: dir
    real(dp), intent(in) :: h, t, q(:), p(:), lambda(:)
    real(dp), intent(inout) :: vel(:), e_arrive
    real(dp), intent(out) :: qn(:), pn(:), lambdan(:), e_step
    integer, intent(out) :: stat
    integer :: n, m, j, jstar, last_gap
    real(dp) :: tau, alpha, alpha_j, consumed, e_minus, s1res
    logical :: landed

    n = self%n; m = self%m
    call apply_settings(self)
    self%sys%dir = dir
    self%n_impacts = 0
    self%cause = ''
    self%a = q; self%pa = p; tau = h; consumed = 0.0_dp
    ! the regular step, from the extrapolated guess
    self%qs = q + real(dir, dp) * h * vel
    call self%sys%put_endpoint(self%x, q, self%qs)
    call self%sys%put_multipliers(self%x, lambda)
    call substep(self, self%a, self%pa, tau, stat)
    if (stat /= VCI_OK) return

    landed = .false.
    last_gap = 0
    do
      if (self%ng == 0) exit
      call self%sys%get_endpoint(self%x, self%b)
      call self%sys%eval_gaps(self%b, self%gb(1:self%ng), stat)
      if (stat /= VCI_OK) then
        call set_cause(self, 'gap evaluation'); return
      end if
      if (all(self%gb(1:self%ng) >= 0.0_dp)) exit
      if (self%n_impacts >= self%settings%max_impacts_per_step) then
        stat = VCI_ERR_TOO_MANY_IMPACTS
        write (self%cause, '(a,i0,a)') 'more than ', self%settings%max_impacts_per_step, &
          ' impacts in one step (persistent contact or chatter)'
        return
      end if
      call self%sys%eval_gaps(self%a, self%ga(1:self%ng), stat)
      if (stat == VCI_OK) call self%sys%eval_gap_gradients(self%a, self%dga(:, 1:self%ng), stat)
      if (stat /= VCI_OK) then
        call set_cause(self, 'gap evaluation at the start of the sub-step'); return
      end if

      ! Already on a wall and moving into it: the impact is at the start of this sub-step.
      jstar = 0
      do j = 1, self%ng
        if (j == last_gap) cycle   ! just reflected there: the motion leaves it (checked in stage 2)
        if (self%gb(j) < 0.0_dp .and. on_wall(self, j) .and. &
            dot_product(self%dga(:, j), self%b - self%a) < 0.0_dp) then
          ! the chord points into the wall; so must the motion as it departs (a curved sub-step
          ! may leave the wall first and come back: that is stage 1's business)
          if (departs_into(self, j, tau, stat)) then
            jstar = j; exit
          end if
          if (stat /= VCI_OK) return
        end if
      end do
      if (jstar > 0) then
        alpha = 0.0_dp
        self%qt = self%a; self%pminus = self%pa
        if (self%settings%impact_energy == VCI_IMPACT_HAMILTONIAN) then
          call self%sys%hamiltonian(self%qt, self%pminus, e_minus, stat)
        else
          if (.not. ieee_is_finite(e_arrive)) call self%arriving_energy(dir, h, e_arrive, stat)
          e_minus = e_arrive
        end if
        if (stat /= VCI_OK) then
          call set_cause(self, 'energy of the arriving sub-step'); return
        end if
        s1res = 0.0_dp
        call self%sys%get_multipliers(self%x, self%lam0)
        call self%sys%put_multipliers(self%best_x, self%lam0)
      else
        ! Stage 1 on every violated wall; the first one reached (smallest alpha) is the impact.
        alpha = huge(1.0_dp)
        do j = 1, self%ng
          if (self%gb(j) >= 0.0_dp) cycle
          call stage_wall(self, j, tau, alpha_j, stat)
          if (stat /= VCI_OK) return
          if (alpha_j < alpha) then
            alpha = alpha_j; jstar = j
            self%best_x(1:self%nsub + 1) = self%x(1:self%nsub + 1)
            s1res = self%last_residual
          end if
        end do
        call self%sys%get_endpoint(self%best_x, self%qt)
        call self%sys%momentum_out(self%best_x, self%a, alpha * tau, self%pminus, stat)
        if (stat == VCI_OK) then
          if (self%settings%impact_energy == VCI_IMPACT_HAMILTONIAN) then
            call self%sys%hamiltonian(self%qt, self%pminus, e_minus, stat)
          else
            call self%sys%energy_out(self%best_x, self%a, alpha * tau, e_minus, stat)
          end if
        end if
        if (stat /= VCI_OK) then
          call set_cause(self, 'momentum at the wall'); return
        end if
        ! Reached the wall (to round-off) exactly at the end of the step: no reflection yet;
        ! the next step starts on the wall and reflects there.
        if (1.0_dp - alpha <= landing_fraction) then
          self%a = self%qt; self%pa = self%pminus
          call self%sys%get_multipliers(self%best_x, lambdan)
          qn = self%qt; pn = self%pminus; e_step = e_minus
          vel = real(dir, dp) * (self%qt - q) / h
          e_arrive = e_minus
          landed = .true.
          exit
        end if
      end if

      ! Stage 2: reflect from (qt, p_minus) over the rest of the sub-step.
      self%vin = (self%b - self%a) / tau
      call stage_reflect(self, jstar, (1.0_dp - alpha) * tau, e_minus, stat)
      if (stat /= VCI_OK) return
      call record_impact(self, dir, h, t, consumed + alpha * tau, jstar, e_minus, s1res, (1.0_dp - alpha) * tau)
      consumed = consumed + alpha * tau
      tau = (1.0_dp - alpha) * tau
      last_gap = jstar
      self%a = self%qt
      self%pa = self%impacts(self%n_impacts)%p_after
      e_arrive = e_minus
    end do
    if (landed) return

    call self%sys%get_endpoint(self%x, qn)
    call self%sys%get_multipliers(self%x, lambdan)
    call self%sys%momentum_out(self%x, self%a, tau, pn, stat)
    if (stat == VCI_OK) call self%sys%energy_out(self%x, self%a, tau, e_step, stat)
    if (stat /= VCI_OK) then
      call set_cause(self, 'momentum of the new state'); return
    end if
    vel = real(dir, dp) * (qn - self%a) / tau
    e_arrive = e_step
  end subroutine advance

  !> Is configuration a (the sub-step's start) on wall j, to solver tolerance?
  logical function on_wall(self, j)
    type(vci_stepper_t), intent(in) :: self
    integer, intent(in) :: j
    real(dp) :: scale
    ! the size of g's terms and of its change over the sub-step (as in stage 1's gap row)
    scale = abs(self%ga(j)) + sum(abs(self%dga(:, j)) * (abs(self%a) + abs(self%b - self%a)))
    on_wall = self%ga(j) <= 10.0_dp * (self%settings%atol + self%settings%rtol * scale)
  end function on_wall

  !> Regular sub-step of length tau from (a, pa); x holds the initial guess and returns the solution.
  subroutine substep(self, a, pa, tau, stat)
    type(vci_stepper_t), intent(inout) :: self
    real(dp), intent(in) :: a(:), pa(:), tau
    integer, intent(out) :: stat
    integer :: nx
    nx = self%nsub
    self%sys%kind = KIND_SUBSTEP
    self%sys%a = a; self%sys%pa = pa; self%sys%tau = tau
    if (self%m > 0) then
      call self%sys%eval_forms(a, self%sys%omega, stat)
      if (stat /= VCI_OK) then
        call set_cause(self, 'constraint forms'); return
      end if
    end if
    call run_newton(self, nx, 'regular step', stat)
  end subroutine substep

  !> Stage 1 for wall j: find alpha in (0, 1], b on the wall, lambda. Initial guess from the chord a -> b.
  subroutine stage_wall(self, j, tau, alpha, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: j
    real(dp), intent(in) :: tau
    real(dp), intent(out) :: alpha
    integer, intent(out) :: stat
    integer :: n, m, i
    real(dp) :: lo, hi, mid
    character(len=40) :: what
    n = self%n; m = self%m
    write (what, '(a,i0,a)') 'stage 1 (reaching wall ', j, ')'
    call self%sys%get_multipliers(self%x, self%lam0)
    ! Initial guess: the first crossing along the chord a -> b, by sampling then bisection (g is cheap).
    lo = 0.0_dp; hi = 1.0_dp
    do i = 1, 8
      mid = real(i, dp) / 8.0_dp
      call chord_gap(self, mid, stat)
      if (stat /= VCI_OK) return
      if (self%gw(j) < 0.0_dp) then
        hi = mid; exit
      end if
      lo = mid
    end do
    do i = 1, 20
      mid = 0.5_dp * (lo + hi)
      call chord_gap(self, mid, stat)
      if (stat /= VCI_OK) return
      if (self%gw(j) > 0.0_dp) then
        lo = mid
      else
        hi = mid
      end if
    end do
    alpha = max(hi, 1.0e-6_dp)
    self%qs = self%a + alpha * (self%b - self%a)
    call self%sys%put_endpoint(self%x, self%a, self%qs)
    call solve_wall(self, j, tau, alpha, trim(what), stat)
    if (stat == VCI_OK) then
      alpha = self%sys%get_extra(self%x, KIND_WALL)
      if (alpha > 0.0_dp .and. alpha <= 1.0_dp) return
    end if
    ! The chord is a poor guess when the sub-step is strongly curved (stiff forces, a second
    ! bounce in one step): bracket the crossing on the discrete trajectory itself, i.e. on the
    ! end points of regular sub-steps of length s tau, and start Newton inside that bracket.
    call trajectory_bracket(self, j, tau, alpha, stat)
    if (stat /= VCI_OK) return
    call solve_wall(self, j, tau, alpha, trim(what), stat)
    if (stat /= VCI_OK) return
    alpha = self%sys%get_extra(self%x, KIND_WALL)
    if (.not. (alpha > 0.0_dp .and. alpha <= 1.0_dp)) then
      stat = VCI_ERR_IMPACT
      write (self%cause, '(a,es10.3,a)') trim(what)//': impact fraction ', alpha, ' outside (0, 1]'
    end if
  end subroutine stage_wall

  !> Does the motion from (a, pa) depart into wall j? Sign of grad g_j . (b_eps - a) for the end
  !> b_eps of a regular sub-step of length 1e-3 tau. Leaves x as it found it.
  logical function departs_into(self, j, tau, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: j
    real(dp), intent(in) :: tau
    integer, intent(out) :: stat
    real(dp), parameter :: eps_frac = 1.0e-3_dp
    integer :: nx
    nx = self%nsub
    self%xhi(1:nx) = self%x(1:nx)
    self%qs = self%a + eps_frac * (self%b - self%a)
    call self%sys%put_endpoint(self%x, self%a, self%qs)
    call substep(self, self%a, self%pa, eps_frac * tau, stat)
    call self%sys%get_endpoint(self%x, self%bt)
    departs_into = stat == VCI_OK .and. dot_product(self%dga(:, j), self%bt - self%a) < 0.0_dp
    self%x(1:nx) = self%xhi(1:nx)
  end function departs_into

  !> Gaps at the chord point a + s (b - a), into gw.
  subroutine chord_gap(self, s, stat)
    type(vci_stepper_t), intent(inout) :: self
    real(dp), intent(in) :: s
    integer, intent(out) :: stat
    self%qs = self%a + s * (self%b - self%a)
    call self%sys%eval_gaps(self%qs, self%gw(1:self%ng), stat)
    if (stat /= VCI_OK) call set_cause(self, 'gap evaluation')
  end subroutine chord_gap

  !> Bracket stage 1's alpha on regular sub-steps of length s tau (8 samples, 8 bisections, then
  !> linear interpolation); leaves the interpolated (b, lambda) in x and alpha.
  subroutine trajectory_bracket(self, j, tau, alpha, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: j
    real(dp), intent(in) :: tau
    real(dp), intent(out) :: alpha
    integer, intent(out) :: stat
    integer :: nm, i
    real(dp) :: lo, hi, mid, glo, ghi, g
    nm = self%nsub
    lo = 0.0_dp; hi = 1.0_dp
    glo = self%ga(j); ghi = self%gb(j)
    call self%sys%put_endpoint(self%xlo, self%a, self%a)
    call self%sys%put_multipliers(self%xlo, self%lam0)
    call self%sys%put_endpoint(self%xhi, self%a, self%b)
    call self%sys%put_multipliers(self%xhi, self%lam0)
    do i = 1, 7                           ! the first crossing: sample from the start ...
      mid = real(i, dp) / 8.0_dp
      call trajectory_gap(self, j, tau, lo, hi, mid, g, stat)
      if (stat /= VCI_OK) return
      if (g < 0.0_dp) then
        hi = mid; ghi = g; self%xhi(1:nm) = self%x(1:nm)
        exit
      end if
      lo = mid; glo = g; self%xlo(1:nm) = self%x(1:nm)
    end do
    do i = 1, 8                           ! ... then bisect the bracket
      mid = 0.5_dp * (lo + hi)
      call trajectory_gap(self, j, tau, lo, hi, mid, g, stat)
      if (stat /= VCI_OK) return
      if (g < 0.0_dp) then
        hi = mid; ghi = g; self%xhi(1:nm) = self%x(1:nm)
      else
        lo = mid; glo = g; self%xlo(1:nm) = self%x(1:nm)
      end if
    end do
    glo = max(glo, 0.0_dp)                ! a start on the wall may be below it by round-off
    alpha = lo + (hi - lo) * glo / max(glo - ghi, tiny(1.0_dp))
    alpha = min(max(alpha, lo + 1.0e-3_dp * (hi - lo)), hi)
    self%x(1:nm) = self%xlo(1:nm) + (alpha - lo) / (hi - lo) * (self%xhi(1:nm) - self%xlo(1:nm))
  end subroutine trajectory_bracket

  !> g_j at the end of the regular sub-step of length s tau (its solution left in x).
  subroutine trajectory_gap(self, j, tau, lo, hi, s, g, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: j
    real(dp), intent(in) :: tau, lo, hi, s
    real(dp), intent(out) :: g
    integer, intent(out) :: stat
    integer :: nm
    nm = self%nsub
    self%x(1:nm) = self%xlo(1:nm) + (s - lo) / (hi - lo) * (self%xhi(1:nm) - self%xlo(1:nm))
    call substep(self, self%a, self%pa, s * tau, stat)
    if (stat /= VCI_OK) return
    call self%sys%get_endpoint(self%x, self%bt)
    call self%sys%eval_gaps(self%bt, self%gw(1:self%ng), stat)
    if (stat /= VCI_OK) then
      call set_cause(self, 'gap evaluation'); return
    end if
    g = self%gw(j)
  end subroutine trajectory_gap

  !> Newton on stage 1 from x(1:n) (and lambda in lam0) with alpha.
  subroutine solve_wall(self, j, tau, alpha, what, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: j
    real(dp), intent(in) :: tau, alpha
    character(len=*), intent(in) :: what
    integer, intent(out) :: stat
    integer :: m
    m = self%m
    call self%sys%put_extra(self%x, KIND_WALL, alpha)
    self%sys%kind = KIND_WALL
    self%sys%a = self%a; self%sys%pa = self%pa; self%sys%tau = tau; self%sys%gap = j
    self%sys%gscale = abs(self%dga(:, j))
    if (m > 0) then
      call self%sys%eval_forms(self%a, self%sys%omega, stat)
      if (stat /= VCI_OK) then
        call set_cause(self, 'constraint forms'); return
      end if
    end if
    call run_newton(self, self%sys%unknowns(KIND_WALL), what, stat)
  end subroutine solve_wall

  !> Stage 2 on wall j from (qt, p_minus) over tau2: q_next, lambda, impulse mu. Newton starts from
  !> the linearised reflection so that it converges to the reflected root, not the pass-through one.
  subroutine stage_reflect(self, j, tau2, e_minus, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: j
    real(dp), intent(in) :: tau2, e_minus
    integer, intent(out) :: stat
    integer :: n, m, nx0, info
    real(dp) :: num, den, mu0
    character(len=40) :: what
    n = self%n; m = self%m; nx0 = self%nsub
    write (what, '(a,i0,a)') 'stage 2 (reflecting at wall ', j, ')'
    call self%sys%eval_gap_gradients(self%qt, self%dga(:, 1:self%ng), stat)
    if (stat /= VCI_OK) then
      call set_cause(self, 'gap gradients at the wall'); return
    end if
    self%sys%grad = self%dga(:, j)
    ! the motion with no impulse, and its sensitivity d = d(q_next, lambda)/d mu
    self%qs = self%qt + tau2 * self%vin
    call self%sys%put_endpoint(self%x, self%qt, self%qs)
    call substep(self, self%qt, self%pminus, tau2, stat)
    if (stat /= VCI_OK) return
    call self%sys%get_endpoint(self%x, self%bt)
    num = dot_product(self%sys%grad, self%bt - self%qt)
    mu0 = 0.0_dp
    if (num < 0.0_dp) then
      call self%sys%residual(self%x(1:nx0), self%r(1:nx0), self%sc(1:nx0), stat)
      if (stat == VCI_OK) call self%sys%jacobian(self%x(1:nx0), self%r(1:nx0), self%jac(1:nx0, 1:nx0), stat)
      if (stat /= VCI_OK) then
        call set_cause(self, trim(what)//' initial guess'); return
      end if
      self%bt = -self%sys%grad
      call self%sys%momentum_rhs(self%bt, self%rhs(1:nx0))
      call self%newton%linear_solve(nx0, self%jac, self%rhs, info)
      call self%sys%endpoint_direction(self%rhs(1:nx0), self%bt)   ! (i14: a sensitivity, not a point)
      den = dot_product(self%sys%grad, self%bt)
      if (info /= 0 .or. .not. (abs(den) > 0.0_dp) .or. .not. ieee_is_finite(den)) then
        stat = VCI_ERR_IMPACT
        self%cause = trim(what)//': the motion does not depend on the impulse (singular normal direction)'
        return
      end if
      mu0 = -2.0_dp * num / den
      self%x(1:nx0) = self%x(1:nx0) + mu0 * self%rhs(1:nx0)
    end if
    ! num >= 0: the free motion from the wall already moves into the admissible set (a graze);
    ! no impulse is needed and the sub-step stands as computed.
    call self%sys%put_extra(self%x, KIND_REFLECT, mu0)
    if (self%m > 0) self%nu = 0.0_dp
    if (mu0 /= 0.0_dp .and. self%settings%impact_energy == VCI_IMPACT_HAMILTONIAN) then
      ! H(qt, p+) = H(qt, p-) fixes the impulse from the momenta alone (with constraints, together
      ! with the constraint impulse nu that makes the outgoing velocity admissible); the leaving
      ! sub-step is then a regular one from p- + mu grad g (Omega nu is absorbed by its multiplier).
      self%best_x(1:nx0) = self%x(1:nx0)
      self%x(1:m) = 0.0_dp                       ! the impulse system's unknowns: [nu(m), mu]
      call self%sys%put_extra(self%x, KIND_IMPULSE, mu0)
      self%sys%kind = KIND_IMPULSE
      self%sys%a = self%qt; self%sys%pa = self%pminus; self%sys%e_minus = e_minus
      if (m > 0) then
        ! start nu where the outgoing velocity satisfies the constraints for the estimated mu
        ! (one linear solve: exact when H is quadratic in p)
        call self%sys%residual(self%x(1:m + 1), self%r(1:m + 1), self%sc(1:m + 1), stat)
        if (stat == VCI_OK) call self%sys%jacobian(self%x(1:m + 1), self%r(1:m + 1), self%jac(1:m + 1, 1:m + 1), stat)
        if (stat /= VCI_OK) then
          call set_cause(self, trim(what)//' impulse initial guess'); return
        end if
        self%rhs(1:m) = -self%r(1:m)
        call self%newton%linear_solve(m, self%jac, self%rhs, info)
        if (info == 0) self%x(1:m) = self%rhs(1:m)
      end if
      call run_newton(self, m + 1, trim(what)//' impulse', stat)
      if (stat /= VCI_OK) return
      mu0 = self%sys%get_extra(self%x, KIND_IMPULSE)
      if (m > 0) self%nu = self%x(1:m)
      self%x(1:nx0) = self%best_x(1:nx0)
      self%pimp = self%pminus + mu0 * self%sys%grad
      call substep(self, self%qt, self%pimp, tau2, stat)
      if (stat /= VCI_OK) return
      call self%sys%put_extra(self%x, KIND_REFLECT, mu0)
      if (.not. reflected(self, mu0, tau2, stat)) then
        if (stat == VCI_OK) stat = VCI_ERR_IMPACT
        self%cause = trim(what)//': the reflected motion does not leave the wall'
        return
      end if
    else if (mu0 /= 0.0_dp) then
      self%sys%kind = KIND_REFLECT
      self%sys%a = self%qt; self%sys%pa = self%pminus; self%sys%tau = tau2; self%sys%gap = j
      self%sys%e_minus = e_minus
      call run_newton(self, self%sys%unknowns(KIND_REFLECT), trim(what), stat)
      if (stat /= VCI_OK) return
      if (.not. reflected(self, self%sys%get_extra(self%x, KIND_REFLECT), tau2, stat)) then
        if (stat == VCI_OK) stat = VCI_ERR_IMPACT
        self%cause = trim(what)//': the reflected motion does not leave the wall'
        return
      end if
    else
      self%last_residual = 0.0_dp
    end if
  end subroutine stage_reflect

  !> Did stage 2 find the reflection? Yes when the sub-step ends on the admissible side of the wall.
  !> A strongly curved sub-step (gravity or a stiff force towards the wall) may leave the wall and
  !> come back to end beyond it: then the motion must depart from the wall — the end of a short
  !> sub-step (1e-3 tau2) from (qt, p- + mu grad g) is on the admissible side — and the re-entry is
  !> the next impact of this step. The pass-through root departs into the wall.
  logical function reflected(self, mu, tau2, stat)
    type(vci_stepper_t), intent(inout) :: self
    real(dp), intent(in) :: mu, tau2
    integer, intent(out) :: stat
    real(dp), parameter :: eps_frac = 1.0e-3_dp
    integer :: nx
    stat = VCI_OK
    call self%sys%get_endpoint(self%x, self%bt)
    reflected = dot_product(self%sys%grad, self%bt - self%qt) > 0.0_dp
    if (reflected) return
    nx = self%sys%unknowns(KIND_REFLECT)
    self%xhi(1:nx) = self%x(1:nx)
    self%qs = self%qt + eps_frac * (self%bt - self%qt)
    call self%sys%put_endpoint(self%x, self%qt, self%qs)
    self%pimp = self%pminus + mu * self%sys%grad
    call substep(self, self%qt, self%pimp, eps_frac * tau2, stat)
    call self%sys%get_endpoint(self%x, self%bt)
    reflected = stat == VCI_OK .and. dot_product(self%sys%grad, self%bt - self%qt) > 0.0_dp
    self%x(1:nx) = self%xhi(1:nx)
    if (.not. reflected) stat = VCI_OK
  end function reflected

  subroutine record_impact(self, dir, h, t, elapsed, j, e_minus, s1res, tau2)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: dir, j
    real(dp), intent(in) :: h, t, elapsed, e_minus, s1res, tau2
    integer :: n, stat
    real(dp) :: mu, e_after
    n = self%n
    mu = self%sys%get_extra(self%x, KIND_REFLECT)
    self%n_impacts = self%n_impacts + 1
    associate (imp => self%impacts(self%n_impacts))
      imp%t = t + real(dir, dp) * elapsed
      imp%alpha = elapsed / h
      imp%gap = j
      imp%q = self%qt
      imp%p_before = self%pminus
      imp%p_after = self%pminus + mu * self%sys%grad
      if (self%m > 0 .and. self%settings%impact_energy == VCI_IMPACT_HAMILTONIAN) &
        imp%p_after = imp%p_after + matmul(self%sys%omega, self%nu)
      imp%grad_g = self%sys%grad
      imp%impulse = real(dir, dp) * mu
      imp%energy_before = e_minus
      if (self%settings%impact_energy == VCI_IMPACT_HAMILTONIAN) then
        call self%sys%hamiltonian(self%qt, imp%p_after, e_after, stat)
      else
        call self%sys%energy_out(self%x, self%qt, tau2, e_after, stat)
      end if
      imp%energy_after = e_after
      call self%sys%get_endpoint(self%x, self%bt)
      imp%leave_rate = dot_product(self%sys%grad, self%bt - self%qt) / tau2
      imp%stage1_residual = s1res
      imp%stage2_residual = self%last_residual
    end associate
  end subroutine record_impact

  !> E_d of the sub-step that would have arrived at the current point in direction dir: one
  !> regular sub-step in the opposite direction (walls ignored). Needed only when a run starts on
  !> a wall moving into it and no previous step is known.
  subroutine arriving_energy(self, dir, h, e, stat)
    class(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: dir
    real(dp), intent(in) :: h
    real(dp), intent(out) :: e
    integer, intent(out) :: stat
    integer :: nx
    nx = self%sys%unknowns(KIND_REFLECT)
    self%best_x(1:nx) = self%x(1:nx)
    self%sys%dir = -dir
    call self%sys%put_endpoint(self%x, self%a, self%a)
    call self%sys%put_multipliers(self%x, self%zm)
    call substep(self, self%a, self%pa, h, stat)
    if (stat == VCI_OK) call self%sys%energy_out(self%x, self%a, h, e, stat)
    self%sys%dir = dir
    self%x(1:nx) = self%best_x(1:nx)
  end subroutine arriving_energy

  !> The momentum p1 at q1 and the discrete energy of the segment from q0 to q1 of length h, forward
  !> (the paper's initial pair). Schemes with interior stages solve for them first (KIND_PAIR).
  subroutine pair_momentum(self, q0, q1, h, p1, e, stat)
    class(vci_stepper_t), intent(inout) :: self
    real(dp), intent(in) :: q0(:), q1(:), h
    real(dp), intent(out) :: p1(:), e
    integer, intent(out) :: stat
    self%sys%dir = 1
    self%cause = ''
    call self%sys%put_endpoint(self%x, q0, q1)
    call self%sys%put_multipliers(self%x, self%zm)
    if (self%sys%needs_pair_solve()) then
      self%sys%kind = KIND_PAIR
      self%sys%a = q0; self%sys%b_target = q1; self%sys%tau = h
      call run_newton(self, self%nsub, 'interior stages of the initial pair', stat)
      if (stat /= VCI_OK) return
    end if
    call self%sys%momentum_out(self%x, q0, h, p1, stat)
    if (stat == VCI_OK) call self%sys%energy_out(self%x, q0, h, e, stat)
    if (stat /= VCI_OK) call set_cause(self, 'momentum of the initial pair')
  end subroutine pair_momentum

  subroutine run_newton(self, nx, what, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: nx
    character(len=*), intent(in) :: what
    integer, intent(out) :: stat
    type(vci_newton_result_t) :: res
    self%sys%failed_callback = ''
    call self%sys%forget_jacobian()
    call self%newton%solve(self%sys, self%x(1:nx), res)
    self%stats%newton_solves = self%stats%newton_solves + 1
    self%stats%newton_iterations = self%stats%newton_iterations + res%iterations
    if (res%used_fallback) self%stats%fallbacks = self%stats%fallbacks + 1
    self%last_residual = res%scaled_residual
    stat = res%status
    if (stat == VCI_OK) return
    select case (res%reason)
    case (NEWTON_MAX_ITERATIONS)
      write (self%cause, '(a,i0,a,es9.2,a)') what//': Newton did not converge in ', res%iterations, &
        ' iterations (scaled residual ', res%scaled_residual, ')'
    case (NEWTON_NO_DESCENT)
      write (self%cause, '(a,es9.2,a)') what//': Newton line search found no decrease (scaled residual ', &
        res%scaled_residual, ')'
    case (NEWTON_SINGULAR)
      self%cause = what//': Newton matrix singular and least-squares solve failed'
    case (NEWTON_EVALUATION)
      if (stat == VCI_ERR_NONFINITE) then
        self%cause = what//': callback '//trim(self%sys%failed_callback)//' returned NaN or Inf'
      else
        self%cause = what//': callback '//trim(self%sys%failed_callback)//' reported failure'
      end if
    end select
  end subroutine run_newton

  subroutine set_cause(self, what)
    type(vci_stepper_t), intent(inout) :: self
    character(len=*), intent(in) :: what
    if (len_trim(self%sys%failed_callback) > 0) then
      self%cause = what//': callback '//trim(self%sys%failed_callback)//' failed or returned NaN/Inf'
    else
      self%cause = what//' failed'
    end if
  end subroutine set_cause
end module vci_stepper
