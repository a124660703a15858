!> The nonlinear systems solved in one step of the (+) or (-) scheme (DESIGN.md §1), written once
!> for both directions. With s = +1 (forward) or -1 (backward) and L^s(a, b, tau) = L_d(a, b, tau)
!> for s = +1, L_d(b, a, tau) for s = -1, where a is the known and b the unknown configuration:
!>
!>   sub-step:  s D1 L^s(a, b, tau) + p_a - Omega(a) lambda = 0,   omega_d(a, b, tau) = 0
!>   stage 1 :  the same with tau = alpha * tau_max, plus g_j(b) = 0          (unknown alpha)
!>   stage 2 :  s D1 L^s(qt, b, tau) + p_minus - Omega(qt) lambda + mu grad g_j(qt) = 0,
!>              omega_d(qt, b, tau) = 0,  E_d(qt, b, tau) = E_minus             (unknown mu)
!>              or, for the Hamiltonian condition, H(qt, p_minus + mu grad g_j) = H(qt, p_minus).
!>
!>   impulse :  (Hamiltonian condition) p+ = p_minus + mu grad g_j + Omega(qt) nu with
!>              H(qt, p+) = H(qt, p_minus) and Omega^T dH/dp(qt, p+) = 0     (unknowns nu, mu)
!>
!> The new momentum is p_b = s D2 L^s(a, b, tau). Unknowns are packed as x = [b(n), lambda(m), extra],
!> except for the impulse system, x = [nu(m), mu].
module vci_step_system
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use vci_kinds, only: dp
  use vci_status, only: VCI_OK, VCI_ERR_CALLBACK, VCI_ERR_NONFINITE, VCI_NOT_PROVIDED
  use vci_model, only: vci_model_t
  use vci_newton, only: vci_system_t
  implicit none
  private

  integer, parameter, public :: KIND_SUBSTEP = 1, KIND_WALL = 2, KIND_REFLECT = 3, KIND_IMPULSE = 4
  integer, parameter, public :: VCI_IMPACT_DISCRETE = 0, VCI_IMPACT_HAMILTONIAN = 1

  type, extends(vci_system_t), public :: vci_step_system_t
    class(vci_model_t), pointer :: model => null()
    integer :: n = 0, m = 0, n_gaps = 0
    integer :: kind = KIND_SUBSTEP
    integer :: dir = 1                   !< s = +1 forward, -1 backward
    real(dp) :: tau = 0.0_dp             !< sub-step length (sub-step, stage 2); alpha * tau is stage 1's
    integer :: gap = 0                   !< wall of stage 1 / stage 2
    integer :: impact_energy = VCI_IMPACT_DISCRETE
    real(dp) :: rtol = 1.0e-12_dp        !< the Newton tolerance, to express the round-off floor in its units
    logical :: has_hessian = .false., has_gap_gradients = .false.
    real(dp), allocatable :: a(:), pa(:), omega(:, :), grad(:), gscale(:)
    real(dp) :: e_minus = 0.0_dp         !< E_d of the arriving sub-step, or H(qt, p_minus)
    ! failure report of the last evaluation
    character(len=32) :: failed_callback = ''
    integer :: failed_stat = 0           !< the stat that callback set (> 0 recoverable, < 0 not)
    ! workspace
    real(dp), allocatable, private :: d1(:), hess(:, :), g(:), dg(:, :), rp(:), rm(:), sp(:), sm(:), xp(:)
    real(dp), allocatable, private :: pplus(:)
    real(dp), allocatable, private :: gp(:), gm(:)   !< all gaps at q +- d e_i (n_gaps may exceed n + m + 1)
    !> sum_j |dR_i/dx_j| |x_j| from the last Jacobian: the round-off floor of row i (positions are
    !> often large next to their change over a step), added to each row's scale
    real(dp), allocatable, private :: jscale(:)
    !> |dR/dx| from the last Jacobian of the current solve (zero until the first one): with it,
    !> sum_j |dR_i/db_j| |b_j - a_j| sizes the kinetic term M (b - a)/tau of a momentum row, which
    !> the row's value alone does not show when it cancels the force term (a body released from
    !> rest: p_a = 0 and D1 -> 0 at the solution, so the row would have no size at all)
    real(dp), allocatable, private :: jabs(:, :)
  contains
    procedure :: forget_jacobian
    procedure :: setup
    procedure :: residual => step_residual
    procedure :: jacobian => step_jacobian
    procedure :: admissible => step_admissible
    procedure :: momentum_out
    procedure :: energy_of
    procedure :: eval_gaps
    procedure :: eval_gap_gradients
    procedure :: eval_forms
    procedure :: hamiltonian
  end type vci_step_system_t

  real(dp), parameter :: fd_rel = 6.0e-6_dp   ! ~ eps**(1/3): central differences balance truncation and round-off

contains

  !> Bind to a model and size the workspace (once, before the step loop); stat /= 0: out of memory.
  subroutine setup(self, model, stat)
    class(vci_step_system_t), intent(inout) :: self
    class(vci_model_t), target, intent(inout) :: model
    integer, intent(out) :: stat
    integer :: n, m, nx
    self%model => model
    n = model%n; m = model%m
    self%n = n; self%m = m; self%n_gaps = model%n_gaps
    nx = n + m + 1
    if (allocated(self%a)) deallocate (self%a, self%pa, self%omega, self%grad, self%gscale, self%d1, &
                                       self%hess, self%g, self%dg, self%rp, self%rm, self%sp, self%sm, &
                                       self%xp, self%pplus, self%jscale, self%jabs, self%gp, self%gm)
    allocate (self%a(n), self%pa(n), self%omega(n, m), self%grad(n), self%gscale(n), self%d1(n), &
              self%hess(n, n), self%g(max(1, model%n_gaps)), self%dg(n, max(1, model%n_gaps)), &
              self%rp(nx), self%rm(nx), self%sp(nx), self%sm(nx), self%xp(nx), self%pplus(n), self%jscale(nx), &
              self%jabs(nx, nx), self%gp(max(1, model%n_gaps)), self%gm(max(1, model%n_gaps)), stat=stat)
    if (stat /= 0) return
    self%omega = 0.0_dp
    self%jscale = 0.0_dp
    self%jabs = 0.0_dp
  end subroutine setup

  !> Number of unknowns of the current kind.
  pure integer function nunk(self)
    class(vci_step_system_t), intent(in) :: self
    nunk = self%n + self%m
    if (self%kind /= KIND_SUBSTEP) nunk = nunk + 1
    if (self%kind == KIND_IMPULSE) nunk = self%m + 1
  end function nunk

  !> Sub-step length at the unknowns x.
  pure real(dp) function step_length(self, x)
    class(vci_step_system_t), intent(in) :: self
    real(dp), intent(in) :: x(:)
    step_length = self%tau
    if (self%kind == KIND_WALL) step_length = x(self%n + self%m + 1) * self%tau
  end function step_length

  !> out = s D1 L^s(a, b, tau)  (forward: D1 L_d(a, b); backward: -D2 L_d(b, a)).
  subroutine d1s(self, a, b, tau, out, stat)
    class(vci_step_system_t), intent(inout) :: self
    real(dp), intent(in) :: a(:), b(:), tau
    real(dp), intent(out) :: out(:)
    integer, intent(out) :: stat
    stat = 0
    if (self%dir > 0) then
      call self%model%d1(a, b, tau, out, stat)
    else
      call self%model%d2(b, a, tau, out, stat)
      out = -out
    end if
    call check(self, stat, out, 'D1/D2 of L_d')
  end subroutine d1s

  !> p_b = s D2 L^s(a, b, tau)  (forward: D2 L_d(a, b); backward: -D1 L_d(b, a)).
  subroutine momentum_out(self, a, b, tau, p, stat)
    class(vci_step_system_t), intent(inout) :: self
    real(dp), intent(in) :: a(:), b(:), tau
    real(dp), intent(out) :: p(:)
    integer, intent(out) :: stat
    stat = 0
    if (self%dir > 0) then
      call self%model%d2(a, b, tau, p, stat)
    else
      call self%model%d1(b, a, tau, p, stat)
      p = -p
    end if
    call check(self, stat, p, 'D1/D2 of L_d')
  end subroutine momentum_out

  !> Discrete energy E_d = -D3 L_d of the segment between a and b (same in both directions).
  subroutine energy_of(self, a, b, tau, e, stat)
    class(vci_step_system_t), intent(inout) :: self
    real(dp), intent(in) :: a(:), b(:), tau
    real(dp), intent(out) :: e
    integer, intent(out) :: stat
    real(dp) :: tmp(1)
    stat = 0
    if (self%dir > 0) then
      call self%model%d3(a, b, tau, e, stat)
    else
      call self%model%d3(b, a, tau, e, stat)
    end if
    e = -e
    tmp(1) = e
    call check(self, stat, tmp, 'D3 of L_d')
  end subroutine energy_of

  subroutine hamiltonian(self, q, p, e, stat)
    class(vci_step_system_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(out) :: stat
    real(dp) :: tmp(1)
    stat = 0
    call self%model%energy(q, p, e, stat)
    tmp(1) = e
    call check(self, stat, tmp, 'energy H(q,p)')
  end subroutine hamiltonian

  subroutine eval_gaps(self, q, g, stat)
    class(vci_step_system_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(out) :: stat
    stat = 0
    call self%model%gaps(q, g, stat)
    call check(self, stat, g, 'gap functions')
  end subroutine eval_gaps

  !> Gradients of all gaps at q (differenced when the model does not supply them).
  subroutine eval_gap_gradients(self, q, dg, stat)
    class(vci_step_system_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(out) :: stat
    integer :: i, ng
    real(dp) :: d
    stat = 0
    if (self%has_gap_gradients) then
      call self%model%gap_gradients(q, dg, stat)
      call check(self, stat, dg(:, 1), 'gap gradients')
      if (stat == VCI_OK .and. size(dg, 2) > 1) call check_matrix(self, stat, dg, 'gap gradients')
      return
    end if
    ng = size(dg, 2)
    self%xp(1:self%n) = q
    do i = 1, self%n
      d = fd_rel * max(abs(q(i)), 1.0_dp)
      self%xp(i) = q(i) + d
      call self%eval_gaps(self%xp(1:self%n), self%gp(1:ng), stat)
      if (stat /= VCI_OK) return
      self%xp(i) = q(i) - d
      call self%eval_gaps(self%xp(1:self%n), self%gm(1:ng), stat)
      if (stat /= VCI_OK) return
      self%xp(i) = q(i)
      dg(i, :) = (self%gp(1:ng) - self%gm(1:ng)) / (2.0_dp * d)
    end do
  end subroutine eval_gap_gradients

  subroutine eval_forms(self, q, omega, stat)
    class(vci_step_system_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: omega(:, :)
    integer, intent(out) :: stat
    stat = 0
    if (self%m == 0) return
    call self%model%constraint_forms(q, omega, stat)
    call check_matrix(self, stat, omega, 'constraint forms')   ! a nonzero stat is VCI_ERR_CALLBACK
  end subroutine eval_forms

  !> Residual rows; with `momentum_rows` false only the constraint and last rows are evaluated
  !> (used to difference those rows when the momentum block comes from the analytic Hessian).
  subroutine rows(self, x, r, sc, momentum_rows, stat)
    class(vci_step_system_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    real(dp), intent(out) :: r(:), sc(:)
    logical, intent(in) :: momentum_rows
    integer, intent(out) :: stat
    integer :: n, m, mu, last, i
    real(dp) :: tau, e, hp, ol, ols
    n = self%n; m = self%m; last = n + m + 1
    tau = step_length(self, x)
    stat = VCI_OK
    if (momentum_rows) then
      call d1s(self, self%a, x(1:n), tau, self%d1, stat)
      if (stat /= VCI_OK) return
      r(1:n) = self%d1 + self%pa
      sc(1:n) = abs(self%d1) + abs(self%pa)
      if (m > 0) then
        ! - Omega lambda and its size, as explicit loops: matmul here allocated temporaries per call
        do i = 1, n
          ol = 0.0_dp; ols = 0.0_dp
          do mu = 1, m
            ol = ol + self%omega(i, mu) * x(n + mu)
            ols = ols + abs(self%omega(i, mu)) * abs(x(n + mu))
          end do
          r(i) = r(i) - ol
          sc(i) = sc(i) + ols
        end do
      end if
      if (self%kind == KIND_REFLECT) then
        r(1:n) = r(1:n) + x(last) * self%grad
        sc(1:n) = sc(1:n) + abs(x(last) * self%grad)
      end if
    end if
    if (m > 0) then
      stat = 0
      call self%model%discrete_constraint(self%a, x(1:n), tau, r(n + 1:n + m), stat)
      call check(self, stat, r(n + 1:n + m), 'discrete constraint')
      if (stat /= VCI_OK) return
      do mu = 1, m
        sc(n + mu) = abs(r(n + mu)) + sum(abs(self%omega(:, mu)) * abs(x(1:n) - self%a)) / tau
      end do
    end if
    select case (self%kind)
    case (KIND_WALL)
      call self%eval_gaps(x(1:n), self%g(1:self%n_gaps), stat)
      if (stat /= VCI_OK) return
      r(last) = self%g(self%gap)
      ! g's size: its value, its terms (grad g . q) and its change over the sub-step
      sc(last) = abs(r(last)) + sum(self%gscale * (abs(x(1:n)) + abs(x(1:n) - self%a)))
    case (KIND_REFLECT)
      if (self%impact_energy == VCI_IMPACT_HAMILTONIAN) then
        self%pplus = self%pa + x(last) * self%grad
        call self%hamiltonian(self%a, self%pplus, hp, stat)
        if (stat /= VCI_OK) return
        r(last) = hp - self%e_minus
        sc(last) = abs(hp) + abs(self%e_minus)
      else
        call self%energy_of(self%a, x(1:n), tau, e, stat)
        if (stat /= VCI_OK) return
        r(last) = e - self%e_minus
        sc(last) = abs(e) + abs(self%e_minus)
      end if
      sc(last) = sc(last) + sum(abs(self%pa) * abs(x(1:n) - self%a)) / tau
    end select
  end subroutine rows

  subroutine step_residual(self, x, r, scale, stat)
    class(vci_step_system_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    real(dp), intent(out) :: r(:), scale(:)
    integer, intent(out) :: stat
    integer :: j
    if (self%kind == KIND_IMPULSE) then
      call impulse_rows(self, x, r, scale, stat)
      return
    end if
    call rows(self, x, r, scale, .true., stat)
    ! size of the kinetic terms of the momentum rows, from the current solve's Jacobian
    if (stat == VCI_OK) then
      do j = 1, self%n
        scale(1:self%n) = scale(1:self%n) + self%jabs(1:self%n, j) * abs(x(j) - self%a(j))
      end do
    end if
    ! round-off floor of each row: a few ulps of sum_j |dR_i/dx_j| |x_j|, in units of rtol
    if (stat == VCI_OK) scale = scale + (8.0_dp * epsilon(1.0_dp) / max(self%rtol, epsilon(1.0_dp))) * &
                                self%jscale(1:size(x))
  end subroutine step_residual

  !> Jacobian: the momentum block from the model's mixed Hessian when it has one, multiplier and
  !> impulse columns analytically, everything else by central differences.
  subroutine step_jacobian(self, x, r, jac, stat)
    class(vci_step_system_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), r(:)
    real(dp), intent(out) :: jac(:, :)
    integer, intent(out) :: stat
    integer :: n, m, nx, j, last
    real(dp) :: tau, d, hp, hm
    n = self%n; m = self%m; nx = nunk(self); last = n + m + 1
    jac = 0.0_dp
    stat = VCI_OK
    if (self%kind == KIND_IMPULSE) then
      call impulse_jacobian(self, x, jac, stat)
      return
    end if
    tau = step_length(self, x)
    ! columns of b
    if (self%has_hessian) then
      if (self%dir > 0) then
        call self%model%mixed_hessian(self%a, x(1:n), tau, self%hess, stat)
        call check_matrix(self, stat, self%hess, 'mixed Hessian')
        if (stat /= VCI_OK) return
        jac(1:n, 1:n) = self%hess
      else
        call self%model%mixed_hessian(x(1:n), self%a, tau, self%hess, stat)
        call check_matrix(self, stat, self%hess, 'mixed Hessian')
        if (stat /= VCI_OK) return
        jac(1:n, 1:n) = -transpose(self%hess)
      end if
      if (nx > n) then
        do j = 1, n
          call fd_column(self, x, j, fd_step(x(j), x(j) - self%a(j)), .false., jac(:, j), stat)
          if (stat /= VCI_OK) return
        end do
      end if
    else
      do j = 1, n
        call fd_column(self, x, j, fd_step(x(j), x(j) - self%a(j)), .true., jac(:, j), stat)
        if (stat /= VCI_OK) return
      end do
    end if
    ! multiplier columns: d/d lambda of -Omega(a) lambda
    if (m > 0) jac(1:n, n + 1:n + m) = -self%omega
    select case (self%kind)
    case (KIND_WALL)       ! alpha enters through the sub-step length
      d = fd_rel * x(last)
      call fd_column(self, x, last, d, .true., jac(:, last), stat)
    case (KIND_REFLECT)    ! mu enters linearly in the momentum rows
      jac(1:n, last) = self%grad
      if (self%impact_energy == VCI_IMPACT_HAMILTONIAN) then
        d = fd_rel * max(abs(x(last)), sqrt(sum(self%pa**2)) / max(sqrt(sum(self%grad**2)), tiny(1.0_dp)))
        self%pplus = self%pa + (x(last) + d) * self%grad
        call self%hamiltonian(self%a, self%pplus, hp, stat)
        if (stat /= VCI_OK) return
        self%pplus = self%pa + (x(last) - d) * self%grad
        call self%hamiltonian(self%a, self%pplus, hm, stat)
        if (stat /= VCI_OK) return
        jac(last, last) = (hp - hm) / (2.0_dp * d)
      end if
    end select
    do j = 1, nx
      self%jscale(j) = sum(abs(jac(j, 1:nx)) * abs(x(1:nx)))
    end do
    self%jabs(1:nx, 1:nx) = abs(jac(1:nx, 1:nx))
  end subroutine step_jacobian

  !> A new solve starts: its Jacobian is not known yet (see jabs).
  subroutine forget_jacobian(self)
    class(vci_step_system_t), intent(inout) :: self
    self%jabs = 0.0_dp
  end subroutine forget_jacobian

  !> The Hamiltonian impact: energy row and, with constraints, the outgoing velocity dH/dp(qt, p+)
  !> annihilated by the constraint forms. dH/dp by central differences: exact for H quadratic in p.
  subroutine impulse_rows(self, x, r, sc, stat)
    class(vci_step_system_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    real(dp), intent(out) :: r(:), sc(:)
    integer, intent(out) :: stat
    integer :: m, i, mu
    real(dp) :: hp, hplus, hminus, d, pmax, noise
    m = self%m
    self%pplus = self%pa + x(m + 1) * self%grad
    if (m > 0) self%pplus = self%pplus + matmul(self%omega, x(1:m))
    call self%hamiltonian(self%a, self%pplus, hp, stat)
    if (stat /= VCI_OK) return
    r(m + 1) = hp - self%e_minus
    sc(m + 1) = abs(hp) + abs(self%e_minus)
    if (m == 0) return
    pmax = max(maxval(abs(self%pplus)), tiny(1.0_dp))
    d = 1.0e-4_dp * pmax
    do i = 1, self%n
      self%xp(i) = self%pplus(i)
      self%pplus(i) = self%xp(i) + d
      call self%hamiltonian(self%a, self%pplus, hplus, stat)
      if (stat /= VCI_OK) return
      self%pplus(i) = self%xp(i) - d
      call self%hamiltonian(self%a, self%pplus, hminus, stat)
      if (stat /= VCI_OK) return
      self%pplus(i) = self%xp(i)
      self%d1(i) = (hplus - hminus) / (2.0_dp * d)      ! outgoing velocity dH/dp
    end do
    noise = 4.0_dp * epsilon(1.0_dp) * abs(hp) / d      ! round-off of the difference quotients
    do mu = 1, m
      r(mu) = dot_product(self%omega(:, mu), self%d1)
      sc(mu) = sum(abs(self%omega(:, mu)) * (abs(self%d1) + noise / max(self%rtol, epsilon(1.0_dp))))
    end do
  end subroutine impulse_rows

  subroutine impulse_jacobian(self, x, jac, stat)
    class(vci_step_system_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    real(dp), intent(out) :: jac(:, :)
    integer, intent(out) :: stat
    integer :: j, nx
    real(dp) :: d, xj, pscale
    real(dp) :: xl(size(x))
    nx = size(x)
    pscale = max(maxval(abs(self%pa)), tiny(1.0_dp))
    xl = x
    do j = 1, nx
      xj = x(j)
      if (j == nx) then
        d = fd_rel * max(abs(xj), pscale / max(maxval(abs(self%grad)), tiny(1.0_dp)))
      else
        d = fd_rel * max(abs(xj), pscale / max(maxval(abs(self%omega(:, j))), tiny(1.0_dp)))
      end if
      xl(j) = xj + d
      call impulse_rows(self, xl, self%rp(1:nx), self%sp(1:nx), stat)
      if (stat /= VCI_OK) return
      xl(j) = xj - d
      call impulse_rows(self, xl, self%rm(1:nx), self%sm(1:nx), stat)
      if (stat /= VCI_OK) return
      xl(j) = xj
      jac(1:nx, j) = (self%rp(1:nx) - self%rm(1:nx)) / (2.0_dp * d)
    end do
  end subroutine impulse_jacobian

  pure real(dp) function fd_step(xj, motion)
    real(dp), intent(in) :: xj, motion
    fd_step = fd_rel * max(abs(xj), abs(motion))
    if (fd_step == 0.0_dp) fd_step = fd_rel
  end function fd_step

  !> Central difference of the residual along unknown j (all rows, or only the non-momentum rows).
  subroutine fd_column(self, x, j, d, all_rows, col, stat)
    class(vci_step_system_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    integer, intent(in) :: j
    real(dp), intent(in) :: d
    logical, intent(in) :: all_rows
    real(dp), intent(inout) :: col(:)
    integer, intent(out) :: stat
    integer :: nx, first
    nx = size(x)
    first = 1
    if (.not. all_rows) first = self%n + 1
    self%xp(1:nx) = x
    self%xp(j) = x(j) + d
    call rows(self, self%xp(1:nx), self%rp(1:nx), self%sp(1:nx), all_rows, stat)
    if (stat /= VCI_OK) return
    self%xp(j) = x(j) - d
    call rows(self, self%xp(1:nx), self%rm(1:nx), self%sm(1:nx), all_rows, stat)
    if (stat /= VCI_OK) return
    col(first:nx) = (self%rp(first:nx) - self%rm(first:nx)) / (2.0_dp * d)
  end subroutine fd_column

  !> Stage 1 keeps the impact fraction inside (0, 1].
  logical function step_admissible(self, x)
    class(vci_step_system_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    step_admissible = .true.
    if (self%kind == KIND_WALL) then
      step_admissible = x(size(x)) > 0.0_dp .and. x(size(x)) <= 1.0_dp
    end if
  end function step_admissible

  !> Turn a callback's return into a library status: nonzero -> VCI_ERR_CALLBACK (negative:
  !> unrecoverable), NaN/Inf -> NONFINITE (recoverable).
  subroutine check(self, stat, values, what)
    class(vci_step_system_t), intent(inout) :: self
    integer, intent(inout) :: stat
    real(dp), intent(in) :: values(:)
    character(len=*), intent(in) :: what
    integer :: i
    if (stat /= 0) then
      self%failed_stat = stat
      if (stat < 0) self%unrecoverable = .true.   ! Newton must not back off from it
      stat = VCI_ERR_CALLBACK
      self%failed_callback = what
      return
    end if
    stat = VCI_OK
    do i = 1, size(values)
      if (.not. (abs(values(i)) <= huge(1.0_dp))) then   ! NaN or +-Inf
        stat = VCI_ERR_NONFINITE
        self%failed_stat = 0
        self%failed_callback = what
        return
      end if
    end do
  end subroutine check

  !> check() for a matrix, without the temporary a reshape would allocate.
  subroutine check_matrix(self, stat, values, what)
    class(vci_step_system_t), intent(inout) :: self
    integer, intent(inout) :: stat
    real(dp), intent(in) :: values(:, :)
    character(len=*), intent(in) :: what
    integer :: j
    call check(self, stat, values(:, 1), what)
    do j = 2, size(values, 2)
      if (stat /= VCI_OK) return
      call check(self, stat, values(:, j), what)
    end do
  end subroutine check_matrix
end module vci_step_system
