!> The Galerkin (Lobatto) scheme of a continuous Lagrangian, order 2s (Marsden & West 2001, §2.6;
!> the variational form of Lobatto IIIA-IIIB). On a segment of length tau from the known point a, q is
!> the polynomial of degree s through control points y_0 = a, y_1, ..., y_s (the new point) at the
!> Lobatto nodes c_i; its velocity at node i is dir W_i with W_i = (1/tau) sum_j D_ij y_j (dir = +1
!> forward, -1 backward: the nodes are symmetric, so the backward segment is the forward one read
!> from its other end), and
!>
!>   L_d = tau sum_i b_i L(y_i, dir W_i),
!>   F_j = dL_d/dy_j = tau b_j dL/dq(y_j, V_j) + dir sum_i b_i D_ij dL/dqdot(y_i, V_i).
!>
!> Sub-step: p_a + dir F_0 = 0 (n momentum rows), F_j = 0 for j = 1..s-1 (interior rows); the new
!> momentum is p_b = dir F_s. Stage 1 adds alpha (tau = alpha tau_max) and g_j(y_s) = 0; stage 2 adds
!> mu (+ mu grad g in the momentum rows) and E_d = E_minus, where the discrete energy is
!> E_d = -dL_d/dtau = sum_i b_i E(y_i, V_i) (the interior points are stationary, so only the explicit
!> tau-dependence counts; checked against a difference quotient in test/core/test_schemes.pf).
!> Unknowns: x = [y_1 - a, ..., y_s - a (n each), extra]: the stage values as increments from the known
!> point (as the retractions, docs/DESIGN.md §6), so that the velocities W_i = (1/tau) sum_j D_ij (y_j - a)
!> are not rounded to ulps of |a|; the interior stages are unknowns of the same Newton system as the
!> new point. The new momentum of a regular sub-step is p_a plus the force impulse (impact_momentum).
!> Constraints (m > 0; docs/SCHEMES.md): unknowns x = [y_1..y_s, Lambda_0..Lambda_(s-1), extra]; the
!> rows of nodes j = 0..s-1 carry the forces tau b_j Omega(y_j) Lambda_j (row 0 times dir), the
!> constraint is tested by the rule, sum_i b_i (2 c_i - 1)^k Omega(y_i)^T V_i = 0 (k = 0..s-1: s m
!> rows), and the far node's force enters only the new momentum, fixed by the end state's constraint
!> (project_end). Symmetric; order 2s measured through impacts (test/core/test_nonholo.pf).
!> The Jacobian is analytic from the Hessian blocks of L at the nodes (the model's or differenced):
!>   dF_j/dy_k = tau b_j Lqq_j d_jk + dir b_j D_jk Lqv_j + dir b_k D_kj Lqv_k^T + (1/tau) sum_i b_i D_ij D_ik Lvv_i.
module vci_scheme_lobatto
  use vci_kinds, only: dp
  use vci_status, only: VCI_OK, VCI_ERR_CALLBACK, VCI_ERR_NONFINITE, VCI_ERR_ARGUMENT, VCI_ERR_MEMORY, VCI_ERR_NEWTON
  use vci_lapack, only: dgetrf, dgetrs
  use vci_lagrangian, only: vci_lagrangian_t, vci_lagrangian_work_t, lagrangian_work_setup, &
                            lagrangian_hessians, lagrangian_hamiltonian
  use vci_lobatto_rule, only: vci_lobatto_rule_t, lobatto_rule, VCI_LOBATTO_MAX_STAGES
  use vci_scheme, only: vci_scheme_t, KIND_SUBSTEP, KIND_STAGE1, KIND_STAGE2, KIND_IMPULSE, KIND_PAIR, vci_fd_rel
  use vci_kernels, only: lobatto_nodes, lobatto_forces, lobatto_blocks, total_of
  implicit none
  private

  type, extends(vci_scheme_t), public :: vci_scheme_lobatto_t
    class(vci_lagrangian_t), pointer :: lag => null()
    type(vci_lobatto_rule_t) :: rule
    integer :: s = 0
    logical :: has_model_energy = .false.
    type(vci_lagrangian_work_t) :: work
    real(dp), allocatable, private :: y(:, :), v(:, :), lq(:, :), lv(:, :), lval(:), f(:, :), fs(:, :)
    real(dp), allocatable, private :: hqq(:, :, :), hqv(:, :, :), hvv(:, :, :), g(:), dg(:, :), tmp(:)
    real(dp), allocatable, private :: jscale(:)
    real(dp), allocatable, private :: wdd(:, :, :)   ! b_i D_ij D_ik (i = 0..s, j = 0..s-1, k = 1..s)
    real(dp), allocatable, private :: wbd(:, :)      ! b_i D_ij (the forces' weights)
    ! the point of the last evaluation (evaluate): the Jacobian and the end momentum that follow a
    ! residual at the same point take its node values instead of calling the model again
    real(dp), allocatable, private :: x_eval(:), a_eval(:)
    real(dp), private :: tau_eval = 0.0_dp
    integer, private :: dir_eval = 0
    logical, private :: have_eval = .false., eval_values = .false.
    ! constraints (m > 0): forms at the nodes, node multipliers, moment weights, their derivatives,
    ! and the end projection's saddle system
    real(dp), allocatable, private :: om(:, :, :), lam(:, :), wmom(:, :), ctv(:, :), dctv(:, :), dol(:, :)
    real(dp), allocatable, private :: op(:, :), omm(:, :), qd(:), kkt(:, :), krhs(:), pbar(:), wv(:), nuw(:)
    real(dp), allocatable, private :: osz(:, :)   ! |Omega(:, j)|_1 |V|_max at node i: the moment rows' sizes
    ! the last regular sub-step's nodes and node multipliers (m > 0: put_quadratic_start), its signed
    ! length, and the weights that extrapolate them to the next step's nodes
    real(dp), allocatable, private :: ypoly(:, :), lpoly(:, :), exq(:, :), exl(:, :)
    real(dp), private :: poly_dh = 0.0_dp
    logical, private :: have_poly = .false., poly_used = .false.
    integer, allocatable, private :: kpiv(:)
  contains
    procedure :: setup
    procedure :: unknowns
    procedure :: scheme_residual
    procedure :: scheme_jacobian
    procedure :: put_endpoint, get_endpoint, put_multipliers, get_multipliers, momentum_rhs
    procedure :: momentum_out, energy_out, hamiltonian
    procedure :: impact_momentum
    procedure :: needs_pair_solve
    procedure :: forget_jacobian
    procedure :: endpoint_direction
    procedure :: put_quadratic_start
    procedure :: end_velocity
    procedure :: put_multiplier_history
    ! (issue 25) the stage polynomial for the poke screen
    procedure :: path_degree, path_point, path_bernstein
    ! (issue 24) the polynomial start in checkpoints
    procedure :: start_memory => lobatto_start_memory
    procedure :: restore_start_memory => lobatto_restore_start
  end type vci_scheme_lobatto_t

contains

  !> Bind lag with s stages (1 <= s <= VCI_LOBATTO_MAX_STAGES); stat = VCI_ERR_ARGUMENT for s out
  !> of range, VCI_ERR_MEMORY when an allocation fails.
  subroutine setup(self, lag, s, has_hessians, has_energy, stat)
    class(vci_scheme_lobatto_t), intent(inout) :: self
    class(vci_lagrangian_t), target, intent(inout) :: lag
    integer, intent(in) :: s
    logical, intent(in) :: has_hessians, has_energy
    integer, intent(out) :: stat
    integer :: n, nx, m, i, j, k
    if (s < 1 .or. s > VCI_LOBATTO_MAX_STAGES) then
      stat = VCI_ERR_ARGUMENT; return
    end if
    call lobatto_rule(s, self%rule, stat)
    if (stat == 0) call self%setup_common(lag, stat)
    if (stat /= 0) then
      stat = VCI_ERR_MEMORY; return
    end if
    self%lag => lag
    self%s = s
    n = lag%n
    call lagrangian_work_setup(self%work, n, stat)
    if (stat /= 0) then
      stat = VCI_ERR_MEMORY; return
    end if
    self%work%has_hessians = has_hessians
    self%has_model_energy = has_energy
    nx = s * n + s * lag%m + 1
    if (allocated(self%y)) deallocate (self%y, self%v, self%lq, self%lv, self%lval, self%f, self%fs, self%hqq, &
                                       self%hqv, self%hvv, self%g, self%dg, self%tmp, self%jscale, self%x_eval, &
                                       self%a_eval, self%wdd, self%wbd)
    if (allocated(self%om)) deallocate (self%om, self%lam, self%wmom, self%ctv, self%dctv, self%dol, self%op, &
                                        self%omm, self%qd, self%kkt, self%krhs, self%pbar, self%wv, self%kpiv, &
                                        self%nuw, self%osz, self%ypoly, self%lpoly, self%exq, self%exl)
    allocate (self%y(n, 0:s), self%v(n, 0:s), self%lq(n, 0:s), self%lv(n, 0:s), self%lval(0:s), self%f(n, 0:s), &
              self%fs(n, 0:s), self%hqq(n, n, 0:s), self%hqv(n, n, 0:s), self%hvv(n, n, 0:s), &
              self%g(max(1, lag%n_gaps)), self%dg(n, 1), self%tmp(n), self%jscale(nx), &
              self%x_eval(nx), self%a_eval(n), self%wdd(0:s, 0:s - 1, s), self%wbd(0:s, 0:s), stat=stat)
    if (stat /= 0) then
      stat = VCI_ERR_MEMORY; return
    end if
    self%jscale = 0.0_dp
    self%have_eval = .false.
    do k = 1, s
      do j = 0, s - 1
        do i = 0, s
          self%wdd(i, j, k) = self%rule%b(i) * self%rule%d(i, j) * self%rule%d(i, k)
        end do
      end do
    end do
    do j = 0, s
      do i = 0, s
        self%wbd(i, j) = self%rule%b(i) * self%rule%d(i, j)
      end do
    end do
    if (lag%m > 0) then
      m = lag%m
      allocate (self%om(n, m, 0:s), self%lam(m, 0:s - 1), self%wmom(0:s - 1, 0:s), self%ctv(m, 0:s), &
                self%dctv(m, n), self%dol(n, n), self%op(n, m), self%omm(n, m), self%qd(n), &
                self%kkt(n + m, n + m), self%krhs(n + m), self%pbar(n), self%wv(n), self%kpiv(n + m), &
                self%nuw(m), self%osz(m, 0:s), self%ypoly(n, 0:s), self%lpoly(m, 0:s - 1), self%exq(0:s, s), &
                self%exl(0:s - 1, 0:s - 1), stat=stat)
      if (stat /= 0) then
        stat = VCI_ERR_MEMORY; return
      end if
      ! Lagrange weights at the next step's nodes 1 + c_j of the polynomials through the last step's
      ! positions (nodes 0..s, degree s) and node multipliers (nodes 0..s-1, degree s - 1)
      do j = 1, s
        do i = 0, s
          self%exq(i, j) = lagrange_weight(self%rule%c(0:s), i, 1.0_dp + self%rule%c(j))
        end do
      end do
      do j = 0, s - 1
        do i = 0, s - 1
          self%exl(i, j) = lagrange_weight(self%rule%c(0:s - 1), i, 1.0_dp + self%rule%c(j))
        end do
      end do
      self%have_poly = .false.
      ! moment weights: the constraint tested against (2c - 1)^k, k = 0..s-1, by the Lobatto rule
      do k = 0, s - 1
        do i = 0, s
          self%wmom(k, i) = self%rule%b(i) * (2.0_dp * self%rule%c(i) - 1.0_dp)**k
        end do
      end do
    end if
  end subroutine setup

  !> A new solve starts: the round-off floor of the last Jacobian (another segment length, perhaps
  !> much shorter) must not size this solve's first residual, or the line search compares merits
  !> taken with different floors. Nor is the last evaluation reused across solves (the model may have
  !> changed between steps).
  subroutine forget_jacobian(self)
    class(vci_scheme_lobatto_t), intent(inout) :: self
    self%jscale = 0.0_dp
    self%have_eval = .false.
  end subroutine forget_jacobian

  pure logical function needs_pair_solve(self)
    class(vci_scheme_lobatto_t), intent(in) :: self
    needs_pair_solve = self%s > 1
  end function needs_pair_solve

  pure integer function unknowns(self, kind)
    class(vci_scheme_lobatto_t), intent(in) :: self
    integer, intent(in) :: kind
    select case (kind)
    case (KIND_SUBSTEP, KIND_PAIR); unknowns = self%s * self%n + self%s * self%m
    case (KIND_IMPULSE); unknowns = self%m + 1
    case default; unknowns = self%s * self%n + self%s * self%m + 1
    end select
  end function unknowns

  subroutine put_endpoint(self, x, a, b)
    class(vci_scheme_lobatto_t), intent(in) :: self
    real(dp), intent(inout) :: x(:)
    real(dp), intent(in) :: a(:), b(:)
    integer :: i, n
    n = self%n
    do i = 1, self%s - 1
      x((i - 1) * n + 1:i * n) = self%rule%c(i) * (b - a)
    end do
    x((self%s - 1) * n + 1:self%s * n) = b - a
  end subroutine put_endpoint

  !> The new point a + (y_s - a), from the sub-step's start a set by the stepper.
  subroutine get_endpoint(self, x, v)
    class(vci_scheme_lobatto_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    real(dp), intent(out) :: v(:)
    v = self%a + x((self%s - 1) * self%n + 1:self%s * self%n)
  end subroutine get_endpoint

  !> The sub-step's positions are the polynomial of degree s through its stage points (issue 25).
  pure integer function path_degree(self)
    class(vci_scheme_lobatto_t), intent(in) :: self
    path_degree = self%s
  end function path_degree

  !> Stage point k (1 <= k < s) of the sub-step solved in x, a + (y_k - a), at node c_k (from the
  !> posed start a, as get_endpoint).
  subroutine path_point(self, x, k, q, c)
    class(vci_scheme_lobatto_t), intent(in) :: self
    real(dp), intent(in) :: x(:)
    integer, intent(in) :: k
    real(dp), intent(out) :: q(:), c
    q = self%a + x((k - 1) * self%n + 1:k * self%n)
    c = self%rule%c(k)
  end subroutine path_point

  !> The rule's weights from node values to Bernstein coefficients (vci_lobatto_rule).
  subroutine path_bernstein(self, w)
    class(vci_scheme_lobatto_t), intent(in) :: self
    real(dp), intent(out) :: w(0:, 0:)
    w(0:self%s, 0:self%s) = self%rule%bern
  end subroutine path_bernstein

  !> The endpoint's part of a change dx of the unknowns: the last increment's.
  subroutine endpoint_direction(self, x, v)
    class(vci_scheme_lobatto_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    real(dp), intent(out) :: v(:)
    v = x((self%s - 1) * self%n + 1:self%s * self%n)
  end subroutine endpoint_direction

  !> The stage polynomial's velocity at the new point (forward time), dir W_s = dir (1/tau) sum_j
  !> D_sj (y_j - a) (issue 27): O(h^s) from the motion's, where the chord of a step with a reflection
  !> in it is O(1) off.
  subroutine end_velocity(self, x, tau, v, known)
    class(vci_scheme_lobatto_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), tau
    real(dp), intent(inout) :: v(:)
    logical, intent(out) :: known
    integer :: j, n
    n = self%n
    v = 0.0_dp
    do j = 1, self%s
      v = v + self%rule%d(self%s, j) * x((j - 1) * n + 1:j * n)
    end do
    v = (real(self%dir, dp) / tau) * v
    known = .true.
  end subroutine end_velocity

  !> Newton's start from the quadratic through the last three points (vci_predictor): stage i at
  !> a + dh (c_i v + c_i (c_i + 1)/2 (v - v_before)), dh = dir h, v and v_before the chord velocities
  !> of the last two steps. Each stage O(h^3) from the solution, where the chord to a guessed endpoint
  !> leaves the interior stages O(h^2) off.
  subroutine put_quadratic_start(self, x, a, dh, v, v_before)
    class(vci_scheme_lobatto_t), intent(inout) :: self
    real(dp), intent(inout) :: x(:)
    real(dp), intent(in) :: a(:), dh, v(:), v_before(:)
    integer :: i, l, n, k
    real(dp) :: c, t
    n = self%n
    self%poly_used = .false.
    if (self%m > 0 .and. self%have_poly) then
      ! with constraints: the last regular step's polynomial, when it ended here with this step and
      ! direction (O(h^(s+1)) from the solution where the quadratic is O(h^3): one Newton iteration
      ! fewer per step on the paper's pendulum; docs/bench/lobatto.md)
      if (self%poly_dh == dh .and. all(self%ypoly(:, self%s) == a)) then
        do i = 1, self%s
          do l = 1, n
            t = 0.0_dp
            do k = 0, self%s - 1   ! (node s is a itself: its term is 0)
              t = t + self%exq(k, i) * (self%ypoly(l, k) - a(l))
            end do
            x((i - 1) * n + l) = t
          end do
        end do
        self%poly_used = .true.
        return
      end if
    end if
    do i = 1, self%s
      c = self%rule%c(i)
      do l = 1, n
        x((i - 1) * n + l) = dh * (c * v(l) + (0.5_dp * c * (c + 1.0_dp)) * (v(l) - v_before(l)))
      end do
    end do
  end subroutine put_quadratic_start

  subroutine put_multipliers(self, x, v)
    class(vci_scheme_lobatto_t), intent(in) :: self
    real(dp), intent(inout) :: x(:)
    real(dp), intent(in) :: v(:)
    integer :: j, o
    do j = 0, self%s - 1   ! every node multiplier (a force: smooth in t, independent of the step length)
      o = self%s * self%n + j * self%m
      if (self%m > 0) x(o + 1:o + self%m) = v
    end do
  end subroutine put_multipliers

  !> Newton's start of the node multipliers: each node's on the polynomial through the last steps'
  !> multipliers of node s - 1 (the one the state keeps), at offsets c_(s-1) - 1, - 2, - 3 steps from
  !> the new step's start, evaluated at the node's own offset c_j (quadratic from depth 3, linear at
  !> depth 2). The multipliers are forces, smooth in t: the same value at every node would leave the
  !> start O(h) off at the nodes far from node s - 1, an extra Newton iteration per step.
  subroutine put_multiplier_history(self, x, depth, lam, lam_before, lam_before2, work)
    class(vci_scheme_lobatto_t), intent(inout) :: self
    real(dp), intent(inout) :: x(:)
    integer, intent(in) :: depth
    real(dp), intent(in) :: lam(:), lam_before(:), lam_before2(:)
    real(dp), intent(inout) :: work(:)
    integer :: j, o, m, i, k
    real(dp) :: r, t
    m = self%m
    if (m == 0) return
    if (self%poly_used .and. depth >= 2) then
      self%poly_used = .false.
      do j = 0, self%s - 1
        o = self%s * self%n + j * m
        do k = 1, m
          t = 0.0_dp
          do i = 0, self%s - 1
            t = t + self%exl(i, j) * self%lpoly(k, i)
          end do
          x(o + k) = t
        end do
      end do
      return
    end if
    do j = 0, self%s - 1
      o = self%s * self%n + j * m
      r = self%rule%c(j) - self%rule%c(max(self%s - 1, 0)) + 1.0_dp   ! the node's offset from the last
      if (depth >= 3) then
        x(o + 1:o + m) = (0.5_dp * (r + 1.0_dp) * (r + 2.0_dp)) * lam - (r * (r + 2.0_dp)) * lam_before + &
                         (0.5_dp * r * (r + 1.0_dp)) * lam_before2
      else if (depth == 2) then
        x(o + 1:o + m) = (1.0_dp + r) * lam - r * lam_before
      else
        x(o + 1:o + m) = lam
      end if
    end do
    if (.false.) work = 0.0_dp
  end subroutine put_multiplier_history

  subroutine get_multipliers(self, x, v)
    class(vci_scheme_lobatto_t), intent(in) :: self
    real(dp), intent(in) :: x(:)
    real(dp), intent(out) :: v(:)
    integer :: o
    ! the multiplier of the last node whose row carries one (node s - 1; node 0 when s = 1)
    o = self%s * self%n + (self%s - 1) * self%m
    if (self%m > 0) v = x(o + 1:o + self%m)
  end subroutine get_multipliers

  subroutine momentum_rhs(self, v, rhs)
    class(vci_scheme_lobatto_t), intent(in) :: self
    real(dp), intent(in) :: v(:)
    real(dp), intent(out) :: rhs(:)
    rhs(1:self%n) = v
    rhs(self%n + 1:) = 0.0_dp
  end subroutine momentum_rhs

  !> Stage values, velocities and the partials of L at the nodes of the segment (a, x, tau);
  !> f(:, j) = F_j and fs(:, j) the size of its terms. With `values`, L at the nodes too. The last
  !> evaluation stands when it was at the same point (the Jacobian and the end momentum follow the
  !> residual at their x). One finiteness test per evaluation: a NaN or Inf among the callbacks'
  !> values reaches the sizes fs of the forces (the callbacks are looked at one by one only then, to
  !> name the one that failed).
  subroutine evaluate(self, x, a, tau, values, stat)
    class(vci_scheme_lobatto_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), a(:), tau
    logical, intent(in) :: values
    integer, intent(out) :: stat
    integer :: i, j, n, s, nv
    real(dp) :: dsign, total
    n = self%n; s = self%s
    nv = s * n + s * self%m
    if (self%have_eval) then
      if (tau == self%tau_eval .and. self%dir == self%dir_eval) then
        if (all(x(1:nv) == self%x_eval(1:nv)) .and. all(a == self%a_eval)) then
          if (values .and. .not. self%eval_values) then
            call node_values(self, stat)   ! (L too, for E_d)
          else
            stat = VCI_OK
          end if
          return
        end if
      end if
    end if
    self%have_eval = .false.
    dsign = real(self%dir, dp)
    call lobatto_nodes(n, s, dsign / tau, self%rule%d, a, x, self%y, self%v)
    stat = 0
    do i = 0, s
      call self%lag%dl_dq(self%y(:, i), self%v(:, i), self%lq(:, i), stat)
      if (stat /= 0) then
        call self%check(stat, self%lq(:, i), 'dL/dq'); return
      end if
      call self%lag%dl_dv(self%y(:, i), self%v(:, i), self%lv(:, i), stat)
      if (stat /= 0) then
        call self%check(stat, self%lv(:, i), 'dL/dqdot'); return
      end if
      if (values) then
        call self%lag%lagrangian(self%y(:, i), self%v(:, i), self%lval(i), stat)
        if (stat /= 0) then
          call self%check(stat, self%lval(i:i), 'L'); return
        end if
      end if
    end do
    call lobatto_forces(n, s, tau, dsign, self%rule%b, self%wbd, self%lq, self%lv, self%f, self%fs)
    total = total_of(n * (s + 1), self%fs)
    if (values) total = total + sum(abs(self%lval))
    if (.not. (total <= huge(1.0_dp))) then
      ! which callback: the first non-finite value, in the order they were called
      do i = 0, s
        call self%check(stat, self%lq(:, i), 'dL/dq')
        if (stat == VCI_OK) call self%check(stat, self%lv(:, i), 'dL/dqdot')
        if (stat == VCI_OK .and. values) call self%check(stat, self%lval(i:i), 'L')
        if (stat /= VCI_OK) return
      end do
    end if
    stat = VCI_OK
    if (self%m > 0) then
      do i = 0, s
        call self%eval_forms(self%y(:, i), self%om(:, :, i), stat)
        if (stat /= VCI_OK) return
        do j = 1, self%m
          self%ctv(j, i) = dot_product(self%om(:, j, i), self%v(:, i))
        end do
      end do
      do j = 0, s - 1
        self%lam(:, j) = x(s * n + j * self%m + 1:s * n + (j + 1) * self%m)
      end do
    end if
    self%x_eval(1:nv) = x(1:nv); self%a_eval(:) = a   ! ((:): no reallocation check)
    self%tau_eval = tau; self%dir_eval = self%dir
    self%have_eval = .true.; self%eval_values = values
  end subroutine evaluate

  !> L at the nodes of the last evaluation (which was without them): stat as evaluate's.
  subroutine node_values(self, stat)
    class(vci_scheme_lobatto_t), intent(inout) :: self
    integer, intent(out) :: stat
    integer :: i
    stat = 0
    do i = 0, self%s
      call self%lag%lagrangian(self%y(:, i), self%v(:, i), self%lval(i), stat)
      call self%check(stat, self%lval(i:i), 'L')
      if (stat /= VCI_OK) return
    end do
    self%eval_values = .true.
  end subroutine node_values

  !> At node y (velocity v, multiplier lam): dol = d(Omega(y) lam)/dy (n x n) and
  !> dctv = d(Omega(y)^T v)/dy at fixed v (m x n), by central differences of the forms.
  subroutine form_derivatives(self, y, v, lam, stat)
    class(vci_scheme_lobatto_t), intent(inout) :: self
    real(dp), intent(in) :: y(:), v(:), lam(:)
    integer, intent(out) :: stat
    integer :: c, mu, i
    real(dp) :: d, t, dom
    self%qd(:) = y
    do c = 1, self%n
      d = vci_fd_rel * max(abs(y(c)), 1.0_dp)
      self%qd(c) = y(c) + d
      call self%eval_forms(self%qd, self%op, stat)
      if (stat /= VCI_OK) return
      self%qd(c) = y(c) - d
      call self%eval_forms(self%qd, self%omm, stat)
      if (stat /= VCI_OK) return
      self%qd(c) = y(c)
      do i = 1, self%n
        self%dol(i, c) = 0.0_dp
      end do
      do mu = 1, self%m
        t = 0.0_dp
        do i = 1, self%n
          dom = (self%op(i, mu) - self%omm(i, mu)) / (2.0_dp * d)
          self%dol(i, c) = self%dol(i, c) + dom * lam(mu)
          t = t + dom * v(i)
        end do
        self%dctv(mu, c) = t
      end do
    end do
  end subroutine form_derivatives

  pure real(dp) function step_length(self, x)
    class(vci_scheme_lobatto_t), intent(in) :: self
    real(dp), intent(in) :: x(:)
    step_length = self%tau
    if (self%kind == KIND_STAGE1) step_length = x(self%s * self%n + self%s * self%m + 1) * self%tau
  end function step_length

  subroutine scheme_residual(self, x, r, scale, stat)
    class(vci_scheme_lobatto_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    real(dp), intent(out) :: r(:), scale(:)
    integer, intent(out) :: stat
    integer :: n, s, j, last, m, k, ro, k0, i, a1
    real(dp) :: tau, e, dsign, rsg, acc, vmax
    n = self%n; s = self%s; m = self%m; last = s * n + s * m + 1
    dsign = real(self%dir, dp)
    tau = step_length(self, x)
    call evaluate(self, x, self%a, tau, self%kind == KIND_STAGE2, stat)
    if (stat /= VCI_OK) return
    if (self%kind == KIND_PAIR) then
      ! the given end as an increment, computed as put_endpoint does
      self%tmp(:) = self%b_target - self%a
      r(1:n) = x((s - 1) * n + 1:s * n) - self%tmp
      scale(1:n) = abs(x((s - 1) * n + 1:s * n)) + abs(self%tmp)
    else
      r(1:n) = self%pa + dsign * self%f(:, 0)
      scale(1:n) = abs(self%pa) + self%fs(:, 0)
      if (self%kind == KIND_STAGE2) then
        r(1:n) = r(1:n) + x(last) * self%grad
        scale(1:n) = scale(1:n) + abs(x(last) * self%grad)
      end if
    end if
    do j = 1, s - 1
      r(j * n + 1:(j + 1) * n) = self%f(:, j)
      scale(j * n + 1:(j + 1) * n) = self%fs(:, j)
    end do
    if (m > 0) then
      ! constraint forces tau b_j Omega(y_j) Lambda_j in the rows of nodes 0..s-1 (row 0 times dir)
      do j = 0, s - 1
        if (j == 0 .and. self%kind == KIND_PAIR) cycle
        rsg = 1.0_dp
        if (j == 0) rsg = dsign
        self%tmp = 0.0_dp
        call add_mat_vec(self%tmp, rsg * tau * self%rule%b(j), self%om(:, :, j), self%lam(:, j))
        r(j * n + 1:(j + 1) * n) = r(j * n + 1:(j + 1) * n) + self%tmp
        scale(j * n + 1:(j + 1) * n) = scale(j * n + 1:(j + 1) * n) + abs(self%tmp)
      end do
      ! the constraint Omega(q)^T qdot tested against (2c - 1)^k by the rule (k = 0..s-1); the
      ! pair (both ends given) has no momentum row: Lambda_0 = 0 in the place of k = 0, whose moment
      ! is fixed by the ends (sum_i b_i V_i is the chord: the rule is exact on the polynomial's derivative)
      k0 = 0
      if (self%kind == KIND_PAIR) then
        r(s * n + 1:s * n + m) = self%lam(:, 0)
        scale(s * n + 1:s * n + m) = abs(self%lam(:, 0))
        k0 = 1
      end if
      ! the size of the terms Omega(:, j)^T V compares: |Omega(:, j)|_1 |V|_max (a product of
      ! components would vanish where the motion is along one axis and the form along another)
      do i = 0, s
        vmax = 0.0_dp
        do a1 = 1, n
          vmax = max(vmax, abs(self%v(a1, i)))
        end do
        do j = 1, m
          acc = 0.0_dp
          do a1 = 1, n
            acc = acc + abs(self%om(a1, j, i))
          end do
          self%osz(j, i) = acc * vmax
        end do
      end do
      do k = k0, s - 1
        ro = s * n + k * m
        do j = 1, m
          acc = 0.0_dp; vmax = 0.0_dp
          do i = 0, s
            acc = acc + self%wmom(k, i) * self%ctv(j, i)
            vmax = vmax + abs(self%wmom(k, i)) * self%osz(j, i)
          end do
          r(ro + j) = acc; scale(ro + j) = vmax
        end do
      end do
    end if
    select case (self%kind)
    case (KIND_STAGE1)
      call self%eval_gaps(self%y(:, s), self%g(1:self%n_gaps), stat)
      if (stat /= VCI_OK) return
      r(last) = self%g(self%gap)
      scale(last) = abs(r(last)) + sum(self%gscale * (abs(self%y(:, s)) + abs(x((s - 1) * n + 1:s * n))))
    case (KIND_STAGE2)
      e = 0.0_dp
      do j = 0, s
        e = e + self%rule%b(j) * (dot_product(self%lv(:, j), self%v(:, j)) - self%lval(j))
      end do
      r(last) = e - self%e_minus
      scale(last) = abs(e) + abs(self%e_minus) + sum(abs(self%pa) * abs(x((s - 1) * n + 1:s * n))) / tau
    end select
    ! round-off floor of each row, in units of rtol: the rounding of summing its 2(s + 1) terms, and
    ! a few ulps of sum_j |dR_i/dx_j| |x_j| (positions large next to their change over the segment)
    scale(1:size(x)) = scale(1:size(x)) * (1.0_dp + real(4 * (s + 1), dp) * epsilon(1.0_dp) / &
                       max(self%rtol, epsilon(1.0_dp))) + (8.0_dp * epsilon(1.0_dp) / &
                       max(self%rtol, epsilon(1.0_dp))) * self%jscale(1:size(x))
  end subroutine scheme_residual

  !> Analytic Jacobian from the Hessian blocks at the nodes (evaluate() at x was the last residual).
  subroutine scheme_jacobian(self, x, r, jac, stat)
    class(vci_scheme_lobatto_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), r(:)
    real(dp), intent(inout) :: jac(:, :)
    integer, intent(out) :: stat
    integer :: n, s, i, j, k, last, nx, c0, a1, m, l, k0, ro, c, nh
    real(dp) :: tau, dsign, rs, wgt, acc
    n = self%n; s = self%s; m = self%m; last = s * n + s * m + 1
    nx = self%unknowns(self%kind)
    dsign = real(self%dir, dp)
    tau = step_length(self, x)
    ! (the residual at x was evaluated last: evaluate() takes its node values)
    call evaluate(self, x, self%a, tau, .false., stat)
    if (stat /= VCI_OK) return
    if (self%work%has_hessians) then
      ! the model's blocks, one finiteness test for all nodes
      do i = 0, s
        stat = 0
        call self%lag%hessians(self%y(:, i), self%v(:, i), self%hqq(:, :, i), self%hqv(:, :, i), self%hvv(:, :, i), stat)
        if (stat /= 0) then
          call self%note_failure(stat, 'Hessian blocks of L')
          stat = VCI_ERR_CALLBACK; return
        end if
      end do
      nh = n * n * (s + 1)
      if (.not. (abs(total_of(nh, self%hqq)) + abs(total_of(nh, self%hqv)) + abs(total_of(nh, self%hvv)) <= &
                 huge(1.0_dp))) then
        if (.not. (all(abs(self%hqq) <= huge(1.0_dp)) .and. all(abs(self%hqv) <= huge(1.0_dp)) .and. &
                   all(abs(self%hvv) <= huge(1.0_dp)))) then
          stat = VCI_ERR_NONFINITE
          call lagrangian_failure(self, stat, 'Hessian blocks of L')
          return
        end if
      end if
    else
      do i = 0, s
        call lagrangian_hessians(self%lag, self%work, self%y(:, i), self%v(:, i), self%hqq(:, :, i), &
                                 self%hqv(:, :, i), self%hvv(:, :, i), stat)
        if (stat /= VCI_OK) then
          call lagrangian_failure(self, stat, 'Hessian blocks of L')
          return
        end if
      end do
    end if
    ! rows j = 0..s-1 (row 0 is the momentum block, times dir; not in the pair), columns k = 1..s
    call lobatto_blocks(n, s, merge(1, 0, self%kind == KIND_PAIR), tau, dsign, self%rule%b, self%rule%d, &
                        self%wdd, self%hqq, self%hqv, self%hvv, jac)
    if (self%kind == KIND_PAIR) then
      do a1 = 1, n
        jac(a1, (s - 1) * n + a1) = 1.0_dp
      end do
    end if
    select case (self%kind)
    case (KIND_STAGE1)
      ! alpha enters through tau: dF_j/dtau = b_j Lq_j - b_j Lqv_j V_j - (dir/tau) sum_i b_i D_ij Lvv_i V_i
      do j = 0, s - 1
        rs = 1.0_dp
        if (j == 0) rs = dsign
        self%tmp = self%lq(:, j)
        call add_mat_vec(self%tmp, -1.0_dp, self%hqv(:, :, j), self%v(:, j))
        self%tmp = self%rule%b(j) * self%tmp
        do i = 0, s   ! (y - c t as y + (-c) t: the same bits)
          call add_mat_vec(self%tmp, -((dsign / tau) * self%rule%b(i) * self%rule%d(i, j)), self%hvv(:, :, i), &
                           self%v(:, i))
        end do
        jac(j * n + 1:(j + 1) * n, last) = rs * self%tau * self%tmp
      end do
      call self%eval_gap_gradient(self%y(:, s), self%gap, self%dg(:, 1), stat)   ! (this wall's only)
      if (stat /= VCI_OK) return
      jac(last, (s - 1) * n + 1:s * n) = self%dg(:, 1)
    case (KIND_STAGE2)
      jac(1:n, last) = self%grad
      ! dE_d/dy_k = b_k (Lqv_k V_k - Lq_k) + (dir/tau) sum_i b_i D_ik Lvv_i V_i
      do k = 1, s
        self%tmp = -self%lq(:, k)
        call add_mat_vec(self%tmp, 1.0_dp, self%hqv(:, :, k), self%v(:, k))
        self%tmp = self%rule%b(k) * self%tmp
        do i = 0, s
          call add_mat_vec(self%tmp, (dsign / tau) * self%rule%b(i) * self%rule%d(i, k), self%hvv(:, :, i), &
                           self%v(:, i))
        end do
        jac(last, (k - 1) * n + 1:k * n) = self%tmp
      end do
    end select
    if (m > 0) then
      ! force columns (Lambda_j) and the forms' dependence on the interior nodes
      do j = 0, s - 1
        if (j == 0 .and. self%kind == KIND_PAIR) cycle
        rs = 1.0_dp
        if (j == 0) rs = dsign
        c0 = s * n + j * m
        wgt = rs * tau * self%rule%b(j)
        do a1 = 1, m   ! (scalar loops: a section of the assumed-shape jac cost ~100 instructions a block)
          do c = 1, n
            jac(j * n + c, c0 + a1) = jac(j * n + c, c0 + a1) + wgt * self%om(c, a1, j)
          end do
        end do
        if (self%kind == KIND_STAGE1) then
          self%tmp = 0.0_dp
          call add_mat_vec(self%tmp, rs * self%tau * self%rule%b(j), self%om(:, :, j), self%lam(:, j))
          jac(j * n + 1:(j + 1) * n, last) = jac(j * n + 1:(j + 1) * n, last) + self%tmp
        end if
      end do
      k0 = 0
      if (self%kind == KIND_PAIR) then
        do a1 = 1, m
          jac(s * n + a1, s * n + a1) = 1.0_dp
        end do
        k0 = 1
      end if
      do l = 1, s
        if (l < s) then
          call form_derivatives(self, self%y(:, l), self%v(:, l), self%lam(:, l), stat)
        else
          self%nuw = 0.0_dp   ! (no row carries the far node's multiplier)
          call form_derivatives(self, self%y(:, l), self%v(:, l), self%nuw, stat)
        end if
        if (stat /= VCI_OK) return
        c0 = (l - 1) * n
        if (l < s) then
          wgt = tau * self%rule%b(l)
          do c = 1, n
            do a1 = 1, n
              jac(l * n + a1, c0 + c) = jac(l * n + a1, c0 + c) + wgt * self%dol(a1, c)
            end do
          end do
        end if
        ! moment rows: d/dy_l sum_i wmom(k, i) Omega(y_i)^T V_i, V_i = (dir/tau) sum_l D_il (y_l - a)
        do k = k0, s - 1
          ro = s * n + k * m
          do c = 1, n
            do a1 = 1, m
              acc = self%wmom(k, l) * self%dctv(a1, c)
              do i = 0, s
                acc = acc + (self%wmom(k, i) * (dsign / tau) * self%rule%d(i, l)) * self%om(c, a1, i)
              end do
              jac(ro + a1, c0 + c) = jac(ro + a1, c0 + c) + acc
            end do
          end do
        end do
      end do
      if (self%kind == KIND_STAGE1) then
        ! the moments scale as 1/tau
        do k = 0, s - 1
          ro = s * n + k * m
          do i = 0, s
            jac(ro + 1:ro + m, last) = jac(ro + 1:ro + m, last) - (self%tau / tau) * self%wmom(k, i) * self%ctv(:, i)
          end do
        end do
      end if
    end if
    do j = 1, nx
      self%jscale(j) = sum(abs(jac(j, 1:nx)) * abs(x(1:nx)))
    end do
  end subroutine scheme_jacobian

  !> The new momentum p_b = dir F_s.
  !> The end momentum of a sub-step beside an impact (stage 1's arrival, the sub-step leaving the
  !> wall), which can be short: F_s = tau sum_j b_j dL/dq_j - sum_(j<s) F_j (the rows of D sum to 0),
  !> and the rows give dir F_0 = -pa (pa with the impulse: p- + mu grad g) and F_j = 0 inside, so
  !>   p_b = dir F_s = pa + dir tau sum_j b_j dL/dq(y_j, V_j),
  !> in which the kinetic terms dL/dqdot, velocities from position differences over tau, cancel. As
  !> dir F_s, their round-off (ulp(|y|) / tau) moved H by 2e-4 at x = 2^17 with 1 - alpha = 1e-6
  !> (test_stab_alpha: test_far_from_origin_lobatto).
  subroutine impact_momentum(self, x, a, tau, p, stat, pa)
    class(vci_scheme_lobatto_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), a(:), tau
    real(dp), intent(out) :: p(:)
    integer, intent(out) :: stat
    real(dp), intent(in), optional :: pa(:)
    integer :: j
    real(dp) :: w
    if (.not. present(pa)) then
      call self%momentum_out(x, a, tau, p, stat); return
    end if
    call evaluate(self, x, a, tau, .false., stat)
    if (stat /= VCI_OK) return
    p = pa
    do j = 0, self%s
      w = real(self%dir, dp) * tau * self%rule%b(j)
      p = p + w * self%lq(:, j)
    end do
    call self%check(stat, p, 'dL/dq')
    if (self%m == 0 .or. stat /= VCI_OK) return
    do j = 0, self%s - 1   ! the constraint forces of nodes 0..s-1
      call add_mat_vec(p, real(self%dir, dp) * tau * self%rule%b(j), self%om(:, :, j), self%lam(:, j))
    end do
    call project_end(self, p, stat)
  end subroutine impact_momentum

  subroutine momentum_out(self, x, a, tau, p, stat, pa)
    class(vci_scheme_lobatto_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), a(:), tau
    real(dp), intent(out) :: p(:)
    integer, intent(out) :: stat
    real(dp), intent(in), optional :: pa(:)   !< p_a: the regular sub-step's momentum from the impulse
    ! a regular sub-step (x solves the one posed): p_a plus the impulse, no kinetic term (its sum of
    ! s + 1 momenta, each from differenced stages, rounds at ulps of |p| times sum_i |b_i D_is|)
    if (present(pa) .and. self%kind == KIND_SUBSTEP) then
      if (tau == self%tau .and. all(a == self%a)) then
        call self%impact_momentum(x, a, tau, p, stat, pa)
        if (stat == VCI_OK .and. self%m > 0) call keep_polynomial(self, x, a, tau)
        return
      end if
    end if
    call evaluate(self, x, a, tau, .false., stat)
    if (stat /= VCI_OK) return
    p = real(self%dir, dp) * self%f(:, self%s)
    if (self%m > 0) call project_end(self, p, stat)
  end subroutine momentum_out

  !> The regular sub-step just solved (x at a, length tau; evaluate() at it was the last call): its
  !> nodes, the endpoint as get_endpoint forms it (the next step's start, compared bit for bit), and
  !> its node multipliers, for the next step's start.
  subroutine keep_polynomial(self, x, a, tau)
    class(vci_scheme_lobatto_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), a(:), tau
    integer :: n, s
    n = self%n; s = self%s
    self%ypoly(:, 0:s - 1) = self%y(:, 0:s - 1)
    self%ypoly(:, s) = a + x((s - 1) * n + 1:s * n)
    self%lpoly(:, :) = self%lam(:, :)
    self%poly_dh = real(self%dir, dp) * tau
    self%have_poly = .true.
  end subroutine keep_polynomial

  !> The polynomial start's memory for a checkpoint: [poly_dh, ypoly(n, 0:s), lpoly(m, 0:s-1)]
  !> when there is one (m > 0, after a regular step), else nothing (size 0). stat: VCI_ERR_MEMORY,
  !> mem unallocated, when there is one and it cannot be copied (a checkpoint without it would
  !> restart correct but not bit for bit: the checkpoint fails instead).
  subroutine lobatto_start_memory(self, mem, stat)
    class(vci_scheme_lobatto_t), intent(in) :: self
    real(dp), allocatable, intent(out) :: mem(:)
    integer, intent(out) :: stat
    integer :: o, j
    if (.not. (self%m > 0 .and. self%have_poly)) then
      allocate (mem(0))   ! (zero size: the runtime's smallest block, tiny and fixed)
      stat = VCI_OK; return
    end if
    ! allocated with stat= and filled column by column (n (s+1) + m s values: the constructor's and
    ! reshape's temporaries ended the program when memory ran out)
    allocate (mem(1 + size(self%ypoly) + size(self%lpoly)), stat=stat)
    if (stat /= 0) then
      stat = VCI_ERR_MEMORY; return
    end if
    mem(1) = self%poly_dh
    o = 1
    do j = lbound(self%ypoly, 2), ubound(self%ypoly, 2)
      mem(o + 1:o + size(self%ypoly, 1)) = self%ypoly(:, j); o = o + size(self%ypoly, 1)
    end do
    do j = lbound(self%lpoly, 2), ubound(self%lpoly, 2)
      mem(o + 1:o + size(self%lpoly, 1)) = self%lpoly(:, j); o = o + size(self%lpoly, 1)
    end do
    stat = VCI_OK
  end subroutine lobatto_start_memory

  !> Take the polynomial start from lobatto_start_memory's vector if it has this scheme's size and
  !> finite values; else none (the quadratic start, as after an initialisation).
  subroutine lobatto_restore_start(self, mem)
    class(vci_scheme_lobatto_t), intent(inout) :: self
    real(dp), intent(in) :: mem(:)
    integer :: ny
    self%have_poly = .false.; self%poly_used = .false.
    if (self%m == 0 .or. .not. allocated(self%ypoly)) return
    ny = size(self%ypoly)
    if (size(mem) /= 1 + ny + size(self%lpoly)) return
    if (.not. all(abs(mem) <= huge(1.0_dp)) .or. mem(1) == 0.0_dp) return   ! finite, a step made it
    self%poly_dh = mem(1)
    self%ypoly = reshape(mem(2:1 + ny), shape(self%ypoly))
    self%lpoly = reshape(mem(2 + ny:), shape(self%lpoly))
    self%have_poly = .true.
  end subroutine lobatto_restore_start

  !> l_i(u) = prod_(k /= i) (u - c_k) / (c_i - c_k): the Lagrange weight of node i at u.
  pure real(dp) function lagrange_weight(c, i, u) result(w)
    real(dp), intent(in) :: c(0:), u
    integer, intent(in) :: i
    integer :: k
    w = 1.0_dp
    do k = 0, size(c) - 1
      if (k /= i) w = w * (u - c(k)) / (c(i) - c(k))
    end do
  end function lagrange_weight

  !> The constraint force of the end node, tau b_s Omega(y_s) Lambda_s, enters only the new momentum:
  !> it is fixed by the end state's constraint, p = pbar + Omega(y_s) nu with
  !> dL/dqdot(y_s, w) = p and Omega(y_s)^T w = 0 (Newton on (w, nu) from w = V_s with the saddle
  !> matrix [Lvv, -Omega; Omega^T, 0], regular where Lvv is singular on directions Omega^T sees, as at
  !> theta = pi of the paper's pendulum; one iteration when L is quadratic in qdot). evaluate() at the
  !> segment was the last call.
  subroutine project_end(self, p, stat)
    class(vci_scheme_lobatto_t), intent(inout) :: self
    real(dp), intent(inout) :: p(:)
    integer, intent(out) :: stat
    integer :: n, m, s, it, info, i
    real(dp) :: err, size_r
    n = self%n; m = self%m; s = self%s
    self%pbar = p
    self%wv = self%v(:, s)
    self%nuw = 0.0_dp
    do it = 1, 12
      stat = 0
      call self%lag%dl_dv(self%y(:, s), self%wv, self%tmp, stat)
      call self%check(stat, self%tmp, 'dL/dqdot')
      if (stat /= VCI_OK) return
      self%krhs(1:n) = self%tmp - self%pbar
      call add_mat_vec(self%krhs(1:n), -1.0_dp, self%om(:, :, s), self%nuw)
      do i = 1, m
        self%krhs(n + i) = dot_product(self%om(:, i, s), self%wv)
      end do
      size_r = max(maxval(abs(self%tmp)), maxval(abs(self%pbar)), tiny(1.0_dp))
      err = max(maxval(abs(self%krhs(1:n))) / size_r, maxval(abs(self%krhs(n + 1:n + m))) / &
                max(maxval(abs(self%om(:, :, s))) * maxval(abs(self%wv)), tiny(1.0_dp)))
      if (it > 1 .and. err <= 64.0_dp * epsilon(1.0_dp)) exit
      if (it == 12) then
        stat = VCI_ERR_NEWTON
        call lagrangian_failure(self, stat, 'end projection onto the constraints')
        return
      end if
      call lagrangian_hessians(self%lag, self%work, self%y(:, s), self%wv, self%hqq(:, :, 0), self%hqv(:, :, 0), &
                               self%hvv(:, :, 0), stat)
      if (stat /= VCI_OK) then
        call lagrangian_failure(self, stat, 'Hessian blocks of L')
        return
      end if
      self%kkt = 0.0_dp
      self%kkt(1:n, 1:n) = self%hvv(:, :, 0)
      self%kkt(1:n, n + 1:n + m) = -self%om(:, :, s)
      do i = 1, m
        self%kkt(n + i, 1:n) = self%om(:, i, s)
      end do
      self%krhs = -self%krhs
      if (.not. (all(abs(self%kkt) <= huge(1.0_dp)) .and. all(abs(self%krhs) <= huge(1.0_dp)))) then
        stat = VCI_ERR_NONFINITE; self%failed_stat = 0; self%failed_callback = 'end projection'; return
      end if
      call dgetrf(n + m, n + m, self%kkt, n + m, self%kpiv, info)
      if (info /= 0) then
        stat = VCI_ERR_NEWTON; self%failed_stat = 0; self%failed_callback = 'end projection (singular)'; return
      end if
      call dgetrs('N', n + m, 1, self%kkt, n + m, self%kpiv, self%krhs, n + m, info)
      self%wv = self%wv + self%krhs(1:n)
      self%nuw = self%nuw + self%krhs(n + 1:n + m)
    end do
    do i = 1, n
      p(i) = self%pbar(i)
      do it = 1, m
        p(i) = p(i) + self%om(i, it, s) * self%nuw(it)
      end do
    end do
    stat = VCI_OK
  end subroutine project_end

  !> E_d = sum_i b_i E(y_i, V_i).
  subroutine energy_out(self, x, a, tau, e, stat)
    class(vci_scheme_lobatto_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), a(:), tau
    real(dp), intent(out) :: e
    integer, intent(out) :: stat
    integer :: j
    e = 0.0_dp
    call evaluate(self, x, a, tau, .true., stat)
    if (stat /= VCI_OK) return
    do j = 0, self%s
      e = e + self%rule%b(j) * (dot_product(self%lv(:, j), self%v(:, j)) - self%lval(j))
    end do
  end subroutine energy_out

  !> H(q, p): the model's, else the Legendre inversion of dL/dqdot.
  subroutine hamiltonian(self, q, p, e, stat)
    class(vci_scheme_lobatto_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(out) :: stat
    real(dp) :: t1(1)
    if (self%has_model_energy) then
      stat = 0
      call self%base%energy(q, p, e, stat)
      t1(1) = e
      call self%check(stat, t1, 'energy H(q,p)')
      return
    end if
    self%tmp = 0.0_dp
    call lagrangian_hamiltonian(self%lag, self%work, q, p, self%tmp, e, stat)
    if (stat /= VCI_OK) call lagrangian_failure(self, stat, 'Legendre inversion for H(q,p)')
  end subroutine hamiltonian

  !> A derived quantity of L failed with status: name it, and when a callback failed keep its code
  !> (a negative one is unrecoverable).
  subroutine lagrangian_failure(self, status, what)
    class(vci_scheme_lobatto_t), intent(inout) :: self
    integer, intent(in) :: status
    character(len=*), intent(in) :: what
    if (status == VCI_ERR_CALLBACK .and. self%work%code /= 0) then
      call self%note_failure(self%work%code, what)
    else
      self%failed_stat = 0
      self%failed_callback = what
    end if
  end subroutine lagrangian_failure

  !> y = y + c matmul(a, v), the product summed in matmul's order: in an expression such as
  !> `y = y + c * matmul(a, v)` gfortran puts matmul's result in a temporary on the heap (at -O0 in
  !> every expression). From y = w, c = -1 it gives w - matmul(a, v) to the bit; from y = -w, c = 1,
  !> matmul(a, v) - w.
  pure subroutine add_mat_vec(y, c, a, v)
    real(dp), intent(inout) :: y(:)
    real(dp), intent(in) :: c, a(:, :), v(:)
    integer :: i, j
    real(dp) :: t
    do i = 1, size(y)
      t = 0.0_dp
      do j = 1, size(v)
        t = t + a(i, j) * v(j)
      end do
      y(i) = y(i) + c * t
    end do
  end subroutine add_mat_vec
end module vci_scheme_lobatto
