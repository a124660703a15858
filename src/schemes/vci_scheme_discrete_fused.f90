!> The regular sub-step's Newton solve in one routine (issue 14: step cost).
!>
!> The general path reaches the same arithmetic through layers: vci_newton%solve calls the residual
!> and the Jacobian through vci_system_t, the scheme dispatches on the system's kind, every vector
!> is a section with its own descriptor and every matrix is checked apart. At n = 2 or 3 those
!> layers cost several times the arithmetic (docs/bench/throughput.md, profile). Here the solve of
!> a posed regular sub-step is one loop on the scheme's own storage: the same rows and row sizes
!> (rows, step_residual), the same Jacobian (momentum_block, constraint_block, the multiplier
!> columns), the same convergence test, start acceptance, Armijo backtracking and polishing chord
!> step as vci_newton%solve, with its in-line LU.
!>
!> Taken only for small systems (n + m <= Newton's small_lu_max, below the simplified-Newton size)
!> whose sub-step Jacobian is analytic: the model's mixed Hessian, and for m > 0 the model's
!> constraint Jacobian or the left retraction's linear constraint. Everything unusual is left to
!> the general path: on a callback's failure, a NaN or Inf, a numerically singular matrix, a line
!> search without decrease or the iteration cap, x is restored and `done` is false, and the caller
!> solves again from the same start with vci_newton%solve (least-squares fallback, backing off
!> from failed trial points, the failure's message). test_schemes compares both paths.
submodule (vci_scheme_discrete) vci_scheme_discrete_fused
  use vci_newton, only: start_roundoff
  use vci_kernels, only: small_lu_solve, substep_rows, substep_direction
  implicit none

contains

  module procedure fused_substep      ! (arguments: the interface in vci_scheme_discrete)
    integer :: nx, it, ib, i, iterations
    real(dp) :: phi, phit, step
    logical :: ok, factored

    done = .false.
    self%flu_kept = .false.
    nx = size(x)
    if (self%kind /= KIND_SUBSTEP .or. nx /= self%n + self%m .or. .not. fusable(self) .or. &
        nx > nw%small_lu_max .or. nx >= nw%reuse_min .or. nx > size(self%fjac, 1)) return
    self%fx0 = x
    self%jac_known = .false.
    self%l_known = .false.     ! (as forget_jacobian)
    iterations = 0
    factored = .false.
    call fused_residual(self, x, self%fr, self%fsc, phi, nw%atol, ok)
    if (.not. ok) return

    do it = 1, nw%max_iterations
      if (phi <= 1.0_dp .and. (it > 1 .or. phi <= start_roundoff)) exit
      iterations = iterations + 1
      call fused_jacobian(self, x, ok)
      if (.not. ok) exit
      call substep_direction(nx, self%fjac, self%sizes, size(self%jabs, 1), self%jabs, self%jscale, self%fr, &
                             self%flu, self%fpiv, self%frw, self%fdx, factored)
      self%jac_known = .true.
      nw%factorisations = nw%factorisations + 1
      if (.not. factored) exit      ! not finite, or numerically singular: the general path's business
      ! Armijo backtracking on the scaled residual (vci_newton%solve)
      step = 1.0_dp
      do ib = 0, nw%max_backtracks
        do i = 1, nx
          self%fxt(i) = x(i) - step * self%fdx(i)
        end do
        call fused_residual(self, self%fxt, self%frt, self%fsct, phit, nw%atol, ok)
        if (.not. ok) exit
        if (phit < (1.0_dp - 1.0e-4_dp * step) * phi) exit
        step = 0.5_dp * step
      end do
      if (.not. ok) then
        factored = .false.; exit
      end if
      if (ib > nw%max_backtracks) then
        if (phi > 1.0_dp) factored = .false.
        exit
      end if
      x = self%fxt
      self%fr = self%frt; self%fsc = self%fsct
      phi = phit
    end do

    if (.not. phi <= 1.0_dp .or. (iterations > 0 .and. .not. factored)) then
      x = self%fx0                                  ! not solved here: the general path takes over
      self%jac_known = .false.
      return
    end if
    ! one chord step with the last factors: about machine precision (vci_newton's polish)
    if (nw%polish .and. factored .and. phi > 0.0_dp) then
      phit = 0.0_dp
      do i = 1, nx
        self%fdx(i) = self%fr(i) * self%frw(i)
        phit = phit + self%fdx(i)
      end do
      if (abs(phit) <= huge(1.0_dp)) then          ! finite
        call small_lu_solve(nx, self%flu, self%fpiv, self%fdx)
        do i = 1, nx
          self%fxt(i) = x(i) - self%fdx(i)
        end do
        call fused_residual(self, self%fxt, self%frt, self%fsct, phit, nw%atol, ok)
        if (ok) then
          iterations = iterations + 1
          if (phit <= phi) then
            x = self%fxt
            phi = phit
          end if
        else if (self%unrecoverable) then
          x = self%fx0                              ! the step ends (vci_stepper: substep)
          self%jac_known = .false.
          return
        end if
      end if
    end if
    res%iterations = iterations
    res%scaled_residual = phi
    self%flu_kept = factored .and. iterations > 0
    done = .true.
  end procedure fused_substep

  module procedure substep_sensitivity   ! (arguments: the interface in vci_scheme_discrete)
    integer :: i, nx
    nx = self%n + self%m
    ok = self%flu_kept .and. size(rhs) == nx
    if (.not. ok) return
    do i = 1, nx
      rhs(i) = rhs(i) * self%frw(i)          ! the rows as equilibrated before factorising
    end do
    call small_lu_solve(nx, self%flu, self%fpiv, rhs)
    ok = abs(sum(rhs)) <= huge(1.0_dp)
  end procedure substep_sensitivity

  !> Is the sub-step's Jacobian analytic (nothing differenced)?
  logical function fusable(self)
    class(vci_scheme_discrete_t), intent(in) :: self
    fusable = self%has_hessian
    if (self%m == 0 .or. .not. fusable) return
    if (self%increments) then
      fusable = self%ret%rule == RETRACTION_LEFT
    else
      fusable = self%has_constraint_jacobian
    end if
  end function fusable

  !> The sub-step's rows and their sizes at x, as step_residual computes them for KIND_SUBSTEP, and
  !> their merit; ok false when a callback failed or a value is not finite (the callbacks' values are
  !> not scanned one by one here: the general path does that when it redoes the solve).
  subroutine fused_residual(self, x, r, sc, phi, atol, ok)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), atol
    real(dp), intent(out) :: r(:), sc(:), phi
    logical, intent(out) :: ok
    integer :: n, m, nx, stat, i
    n = self%n; m = self%m; nx = n + m
    ok = .false.
    ! d1s's and momentum_block's work written out here: called from this file (a submodule) they are
    ! not inlined, and the calls cost ~6 % of a step (callgrind); the values are scanned as a whole
    stat = 0
    if (self%increments) then
      call self%ret%d1s_inc(self%a, x(1:n), self%tau, self%dir, self%d1, stat)
    else if (self%has_fused .and. self%dir > 0) then
      call ld_at(self, self%a, x(1:n), self%tau, stat)
      do i = 1, n
        self%d1(i) = self%ld1(i)
      end do
    else if (self%has_fused) then
      call ld_at(self, x(1:n), self%a, self%tau, stat)
      do i = 1, n
        self%d1(i) = -self%ld2(i)
      end do
    else if (self%dir > 0) then
      call self%model%d1(self%a, x(1:n), self%tau, self%d1, stat)
    else
      call self%model%d2(x(1:n), self%a, self%tau, self%d1, stat)
      do i = 1, n
        self%d1(i) = -self%d1(i)
      end do
    end if
    if (stat /= 0) then
      call note_if_unrecoverable(self, stat, 'D1/D2 of L_d'); return
    end if
    if (m > 0) then
      if (self%increments) then          ! (constraint_values, inlined as above)
        call self%ret%constraint_inc(self%a, x(1:n), self%tau, r(n + 1:nx), stat)
      else
        call self%model%discrete_constraint(self%a, x(1:n), self%tau, r(n + 1:nx), stat)
      end if
      if (stat /= 0) then
        call note_if_unrecoverable(self, stat, 'discrete constraint'); return
      end if
    end if
    ! (the round-off floor: a few ulps of sum_j |J_ij| |x_j|, in units of rtol, as step_residual)
    call substep_rows(n, m, x, self%a, self%increments, self%d1, self%pa, self%omega, self%tau, self%jac_known, &
                      size(self%jabs, 1), self%jabs, 8.0_dp * epsilon(1.0_dp) / max(self%rtol, epsilon(1.0_dp)), &
                      self%jscale, atol, self%rtol, r, sc, self%kin, phi, ok)
  end subroutine fused_residual

  !> fjac = dR/dx at x (step_jacobian's analytic case) and the unknowns' sizes (for jscale). The
  !> model's matrices are not scanned for NaN/Inf here: the equilibrated matrix is, as a whole.
  subroutine fused_jacobian(self, x, ok)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    logical, intent(out) :: ok
    integer :: n, m, nx, i, j, stat
    n = self%n; m = self%m; nx = n + m
    ok = .false.
    stat = 0
    if (self%increments) then
      self%hess = 0.0_dp      ! (a declared band is written alone; fused systems are small)
      call self%ret%jacobian_inc(self%a, x(1:n), self%tau, self%dir, self%hess, stat)
    else if (self%has_fused) then
      ! the residual at x came just before (fused_substep): its call's Hessian is kept (l_known);
      ! ld_at only when it is not
      if (.not. self%l_known) then
        if (self%dir > 0) then
          call ld_at(self, self%a, x(1:n), self%tau, stat)
        else
          call ld_at(self, x(1:n), self%a, self%tau, stat)
        end if
      end if
    else if (self%dir > 0) then
      call self%model%mixed_hessian(self%a, x(1:n), self%tau, self%hess, stat)
    else
      call self%model%mixed_hessian(x(1:n), self%a, self%tau, self%hess, stat)
    end if
    if (stat /= 0) then
      call note_if_unrecoverable(self, stat, 'mixed Hessian'); return
    end if
    if (self%has_fused .and. .not. self%increments) then
      call kept_hessian_block(n, self%dir, self%lhess, self%fjac)   ! (no copy through hess)
    else if (self%increments .or. self%dir > 0) then
      do j = 1, n
        do i = 1, n
          self%fjac(i, j) = self%hess(i, j)
        end do
      end do
    else
      do j = 1, n
        do i = 1, n
          self%fjac(i, j) = -self%hess(j, i)
        end do
      end do
    end if
    if (m > 0) then
      call constraint_block(self, x, self%tau, self%fjac, stat)
      if (stat /= VCI_OK) return
      do j = 1, m
        do i = 1, n
          self%fjac(i, n + j) = -self%omega(i, j)
        end do
        do i = 1, m
          self%fjac(n + i, n + j) = 0.0_dp    ! (equilibrate scales fjac in place)
        end do
      end do
    end if
    if (self%increments) then
      do j = 1, n
        self%sizes(j) = abs(self%a(j) + x(j))     ! position(self, x, j), inlined
      end do
    else
      do j = 1, n
        self%sizes(j) = abs(x(j))
      end do
    end if
    do j = n + 1, nx
      self%sizes(j) = abs(x(j))
    end do
    ok = .true.
  end subroutine fused_jacobian

  !> The position block of fjac from the fused callback's kept mixed Hessian: itself forward,
  !> minus its transpose backward (explicit shapes: fjac is (n + m) x (n + m), lhess n x n).
  subroutine kept_hessian_block(n, dir, lhess, fjac)
    integer, intent(in) :: n, dir
    real(dp), intent(in) :: lhess(n, n)
    real(dp), intent(inout) :: fjac(:, :)
    integer :: i, j
    if (dir > 0) then
      do j = 1, n
        do i = 1, n
          fjac(i, j) = lhess(i, j)
        end do
      end do
    else
      do j = 1, n
        do i = 1, n
          fjac(i, j) = -lhess(j, i)
        end do
      end do
    end if
  end subroutine kept_hessian_block

  !> A callback's failure in the fused solve: a recoverable one (stat > 0) is left to the general
  !> path, which solves again and backs off; an unrecoverable one (stat < 0) is noted like the
  !> general path's checks do, so that the step ends at once instead (vci_stepper: substep).
  subroutine note_if_unrecoverable(self, stat, what)
    class(vci_scheme_discrete_t), intent(inout) :: self
    integer, intent(in) :: stat
    character(len=*), intent(in) :: what
    if (stat < 0) call self%note_failure(stat, what)
  end subroutine note_if_unrecoverable
end submodule vci_scheme_discrete_fused
