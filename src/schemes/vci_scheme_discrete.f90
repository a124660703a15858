!> The scheme of a discrete Lagrangian given in closed form (docs/DESIGN.md §1, §3): a user's L_d
!> (vci_model_t), or the `left` / `midpoint` retraction of a continuous L (vci_retraction). With
!> s = +1 (forward) or -1 (backward) and L^s(a, b, tau) = L_d(a, b, tau) for s = +1, L_d(b, a, tau)
!> for s = -1, where a is the known and b the unknown configuration:
!>
!>   sub-step:  s D1 L^s(a, b, tau) + p_a - Omega(a) lambda = 0,   omega_d(a, b, tau) = 0
!>   stage 1 :  the same with tau = alpha * tau_max, plus g_j(b) = 0          (unknown alpha)
!>   stage 2 :  s D1 L^s(qt, b, tau) + p_minus - Omega(qt) lambda + mu grad g_j(qt) = 0,
!>              omega_d(qt, b, tau) = 0,  E_d(qt, b, tau) = E_minus             (unknown mu)
!>              or, for the Hamiltonian condition, H(qt, p_minus + mu grad g_j) = H(qt, p_minus).
!>
!> The new momentum is p_b = s D2 L^s(a, b, tau). Layout: x = [b(n), lambda(m), extra] for a user's
!> L_d; x = [d(n), lambda(m), extra] with the increment d = b - a for a retraction of a continuous L
!> (`increments`), whose closed form takes d itself (vci_retraction: no round-off of b - a).
module vci_scheme_discrete
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use vci_kinds, only: dp
  use vci_status, only: VCI_OK
  use vci_model, only: vci_model_t
  use vci_retraction, only: vci_retraction_model_t, RETRACTION_LEFT
  use vci_newton, only: vci_large_system, vci_newton_t, vci_newton_result_t
  use vci_sparse, only: vci_sparse_pattern_t
  use vci_banded_matrix, only: vci_band_matrix_t
  use vci_sparse_matrix, only: vci_sparse_matrix_t
  use vci_kernels, only: momentum_terms, kinetic_and_floor, jacobian_sizes, band_jacobian_sizes
  use vci_scheme, only: vci_scheme_t, KIND_SUBSTEP, KIND_STAGE1, KIND_STAGE2, KIND_IMPULSE, KIND_PAIR, &
                        VCI_IMPACT_HAMILTONIAN, vci_fd_rel
  implicit none
  private
  ! for the fused solve's submodule: gfortran gives private module procedures local linkage, which a
  ! submodule in another file cannot reach (not part of the library's API: `use vci` omits them)
  public :: constraint_block, ld_at

  type, extends(vci_scheme_t), public :: vci_scheme_discrete_t
    class(vci_model_t), pointer :: model => null()
    class(vci_retraction_model_t), pointer :: ret => null()   !< the model, when it is a retraction
    logical :: increments = .false.   !< x(1:n) is the increment d = b - a (retractions)
    !> Compensated positions (increments only): end_key is the endpoint get_endpoint returned last
    !> and end_lo the part of a + d its rounding dropped; start_* the same for the current start
    real(dp), allocatable, private :: start_key(:), start_lo(:), end_key(:), end_lo(:)
    logical, private :: have_end = .false.
    logical :: has_hessian = .false.
    logical :: has_constraint_jacobian = .false.   !< the model's d omega_d (user L_d only)
    !> The model's fused callback (vci_model_t%ld_fused) replaces d1, d2, d3 and mixed_hessian
    !> (user L_d only); its values at the last point (lkey = (q_i, v_i) pairs, lh) are kept, so the
    !> residual, the Jacobian and the new momentum at one point cost one call (issue 26)
    logical :: has_fused = .false.
    real(dp), allocatable, private :: lkey(:, :), ld1(:), ld2(:), lhess(:, :)
    real(dp), private :: lh = 0.0_dp, ld3 = 0.0_dp
    logical, private :: l_known = .false.
    real(dp), allocatable, private :: cjo(:, :)   !< the model's d omega_d(a, b) / db
    real(dp), allocatable, private :: d1(:), hess(:, :), g(:), rp(:), rm(:), sp(:), sm(:), xp(:), bb(:)
    real(dp), allocatable, private :: gg1(:)   !< the wall's gap gradient at stage 1's b (its Jacobian's last row)
    real(dp), allocatable, private :: fcol(:)  !< one differenced column, before it goes into band storage
    !> sum_j |dR_i/dx_j| |x_j| from the last Jacobian: the round-off floor of row i (positions are
    !> often large next to their change over a step), added to each row's scale
    real(dp), allocatable, private :: jscale(:)
    real(dp), allocatable, private :: sizes(:)   !< |b_j| and |x_j| that jscale weighs the Jacobian's entries by
    !> |dR/dx| from the last Jacobian of the current solve (zero until the first one): with it,
    !> sum_j |dR_i/db_j| |b_j - a_j| sizes the kinetic term M (b - a)/tau of a momentum row, which
    !> the row's value alone does not show when it cancels the force term (a body released from
    !> rest: p_a = 0 and D1 -> 0 at the solution, so the row would have no size at all)
    real(dp), allocatable, private :: jabs(:, :)
    logical, private :: jac_known = .false.   !< jabs holds this solve's Jacobian
    !> Large systems (vci_large_system unknowns or more): sum_j |dR_i/db_j| |b_j - a_j| is taken at
    !> the last Jacobian's point (kin) instead of at every residual: O(n) per residual, not O(n^2)
    real(dp), allocatable, private :: kin(:)
    !> Scan every callback's values for NaN/Inf (set only to name the culprit after the residual,
    !> checked once as a whole, turned out non-finite: the hot path checks one sum per residual)
    logical, private :: scan_values = .false.
    !> Workspace of the fused regular-step solve (vci_scheme_discrete_fused), sized n + m
    real(dp), allocatable, private :: fjac(:, :), flu(:, :), fr(:), fsc(:), frt(:), fsct(:), fxt(:), &
                                      fdx(:), frw(:), fx0(:)
    integer, allocatable, private :: fpiv(:)
    !> flu, fpiv, frw hold the factors of the last fused solve's Newton matrix (near its solution)
    logical, private :: flu_kept = .false.
    !> jscale, jabs, kin and jac_known as keep_row_sizes kept them (jabs only below vci_large_system)
    real(dp), allocatable, private :: jscale_kept(:), jabs_kept(:, :), kin_kept(:)
    logical, private :: jac_known_kept = .false.
  contains
    procedure :: setup
    procedure :: unknowns
    procedure :: scheme_residual => step_residual
    procedure :: scheme_jacobian => step_jacobian
    procedure :: put_endpoint, get_endpoint, put_multipliers, get_multipliers, momentum_rhs
    procedure :: endpoint_direction
    procedure :: momentum_out, energy_out, hamiltonian
    procedure :: impact_momentum
    procedure :: forget_jacobian
    procedure :: keep_row_sizes => discrete_keep_row_sizes
    procedure :: restore_row_sizes => discrete_restore_row_sizes
    procedure :: chord_ratio => substep_chord_ratio
    procedure :: block_key => stage_block_key
    procedure :: fused_substep
    procedure :: substep_sensitivity
    procedure :: use_derivatives
    procedure :: structure => banded_structure
    procedure :: packs_band => discrete_packs_band
    procedure :: band_jacobian => step_band_jacobian
    procedure :: sparse_structure => declared_pattern
    procedure :: packs_sparse => discrete_packs_sparse
    procedure :: sparse_jacobian => step_sparse_jacobian
    procedure :: position_carry => discrete_position_carry
    procedure :: restore_position_carry => discrete_restore_carry
  end type vci_scheme_discrete_t

  interface
    !> The regular sub-step's Newton solve in one routine (vci_scheme_discrete_fused.f90).
    module subroutine fused_substep(self, nw, x, res, done)
      class(vci_scheme_discrete_t), intent(inout) :: self
      type(vci_newton_t), intent(inout) :: nw
      real(dp), intent(inout) :: x(:)
      type(vci_newton_result_t), intent(inout) :: res
      logical, intent(out) :: done
    end subroutine fused_substep
    !> J d = rhs with the last fused solve's factors (vci_scheme_discrete_fused.f90).
    module subroutine substep_sensitivity(self, rhs, ok)
      class(vci_scheme_discrete_t), intent(inout) :: self
      real(dp), intent(inout) :: rhs(:)
      logical, intent(out) :: ok
    end subroutine substep_sensitivity
  end interface

contains

  !> Newton's view of the matrix (vci_banded): with a declared Hessian bandwidth, the position
  !> unknowns x(1:n) form a band block (D1 D2 L_d has the Hessians' band) and the multipliers, alpha
  !> or mu are its dense border; the impulse system [nu, mu] has no such block. Else dense.
  subroutine banded_structure(self, nb, bw, check)
    class(vci_scheme_discrete_t), intent(inout) :: self
    integer, intent(out) :: nb, bw
    logical, intent(out) :: check
    nb = 0; bw = -1; check = .false.
    if (self%kind == KIND_IMPULSE .or. .not. associated(self%base)) return
    if (self%base%hessian_bandwidth < 0) return
    nb = self%n; bw = self%base%hessian_bandwidth; check = self%base%check_bandwidth
  end subroutine banded_structure

  !> Newton's view with a declared sparse Hessian pattern (vci_sparse): the position unknowns
  !> x(1:n) form a block with the Hessians' pattern (D1 D2 L_d, and the retraction's Jacobian, is a
  !> sum of the Hessian blocks and their transposes), the multipliers, alpha or mu its dense border.
  subroutine declared_pattern(self, nb, pat, check)
    class(vci_scheme_discrete_t), intent(inout) :: self
    integer, intent(out) :: nb
    type(vci_sparse_pattern_t), pointer, intent(out) :: pat
    logical, intent(out) :: check
    nb = 0; pat => null(); check = .false.
    if (self%kind == KIND_IMPULSE .or. .not. associated(self%base)) return
    if (self%base%hessian_pattern%n /= self%n .or. self%base%hessian_bandwidth >= 0) return
    nb = self%n; pat => self%base%hessian_pattern; check = self%base%check_pattern
  end subroutine declared_pattern

  !> The model's mixed Hessian, discrete constraint Jacobian and gap gradients (each differenced
  !> when the model does not supply it).
  !> fused: the model's ld_fused, which brings its own mixed Hessian (has_hessian follows: give
  !> mixed_hessian before fused, as the driver's probe does).
  subroutine use_derivatives(self, mixed_hessian, gap_gradients, constraint_jacobian, fused)
    class(vci_scheme_discrete_t), intent(inout) :: self
    logical, intent(in), optional :: mixed_hessian, gap_gradients, constraint_jacobian, fused
    if (present(gap_gradients)) self%has_gap_gradients = gap_gradients
    if (present(mixed_hessian)) self%has_hessian = mixed_hessian
    if (present(constraint_jacobian)) self%has_constraint_jacobian = constraint_jacobian
    if (present(fused)) then
      self%has_fused = fused .and. .not. self%increments
      self%has_hessian = self%has_hessian .or. self%has_fused
    end if
    self%l_known = .false.
  end subroutine use_derivatives

  !> The fused callback's values at (q, v, h) into ld1, ld2, ld3, lhess: kept from the last call
  !> when it was at the same point (a failed call is not kept, so it is called again, as a separate
  !> callback would be). stat: the callback's own (checked by the caller, on the values it takes).
  subroutine ld_at(self, q, v, h, stat)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    integer, intent(out) :: stat
    stat = 0
    if (self%l_known .and. h == self%lh) then
      if (same_point(self%n, q, v, self%lkey)) return
    end if
    self%l_known = .false.
    call self%model%ld_fused(q, v, h, self%ld1, self%ld2, self%ld3, self%lhess, stat)
    if (stat /= 0) return
    call keep_point(self%n, q, v, self%lkey)
    self%lh = h
    self%l_known = .true.
  end subroutine ld_at

  !> (q, v) == the kept point, element by element (explicit shapes: no descriptors at n = 2 or 3).
  pure logical function same_point(n, q, v, key)
    integer, intent(in) :: n
    real(dp), intent(in) :: q(n), v(n), key(2, n)
    integer :: i
    same_point = .false.
    do i = 1, n
      if (q(i) /= key(1, i) .or. v(i) /= key(2, i)) return
    end do
    same_point = .true.
  end function same_point

  !> key = the pairs (q_i, v_i), interleaved: two separate arrays made gfortran -O3 turn the loop
  !> into two memcpy calls, which at n = 2 or 3 cost more than the copy (callgrind, pendulum).
  pure subroutine keep_point(n, q, v, key)
    integer, intent(in) :: n
    real(dp), intent(in) :: q(n), v(n)
    real(dp), intent(out) :: key(2, n)
    integer :: i
    do i = 1, n
      key(1, i) = q(i); key(2, i) = v(i)
    end do
  end subroutine keep_point

  !> The low part of q kept by get_endpoint when q is the last endpoint it returned, or the start
  !> of the sub-step it read last (a side computation from other starts, vci_impacts'
  !> poke_seen_from_end, keeps it across them), else zero.
  subroutine discrete_position_carry(self, q, lo)
    class(vci_scheme_discrete_t), intent(in) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: lo(:)
    lo = 0.0_dp
    if (.not. self%increments .or. .not. self%have_end) return
    if (all(q == self%end_key)) then
      lo = self%end_lo
    else if (all(q == self%start_key)) then
      lo = self%start_lo
    end if
  end subroutine discrete_position_carry

  !> Make q the last endpoint, with low part lo, so that the next sub-step from q adds lo back.
  subroutine discrete_restore_carry(self, q, lo)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), lo(:)
    if (.not. self%increments) return
    self%end_key = q; self%end_lo = lo; self%have_end = .true.
    self%start_key = huge(1.0_dp)   ! the next sub-step's start is looked up again
  end subroutine discrete_restore_carry

  !> Bind to a model and size the workspace (once, before the step loop); stat /= 0: out of memory.
  subroutine setup(self, model, stat)
    class(vci_scheme_discrete_t), intent(inout) :: self
    class(vci_model_t), target, intent(inout) :: model
    integer, intent(out) :: stat
    integer :: n, m, nx, nf, nj, nh
    call self%setup_common(model, stat)
    if (stat /= 0) return
    self%model => model
    self%ret => null()
    self%increments = .false.
    select type (model)
    class is (vci_retraction_model_t)
      self%ret => model
      self%increments = .true.
    end select
    n = model%n; m = model%m
    nx = n + m + 1
    if (allocated(self%d1)) deallocate (self%d1, self%hess, self%g, self%rp, self%rm, self%sp, self%sm, &
                                        self%xp, self%jscale, self%jabs, self%bb, self%start_key, &
                                        self%start_lo, self%end_key, self%end_lo, self%kin, self%cjo, self%sizes, &
                                        self%fjac, self%flu, self%fr, self%fsc, self%frt, self%fsct, self%fxt, &
                                        self%fdx, self%frw, self%fx0, self%fpiv, self%gg1, self%fcol, &
                                        self%lkey, self%ld1, self%ld2, self%lhess, self%jscale_kept, &
                                        self%jabs_kept, self%kin_kept)
    ! the fused solve's matrices only for the small systems it takes (vci_large_system; else 1 x 1:
    ! a chain of n = 4096 kept two n x n arrays here, one of them zeroed and so resident)
    nf = merge(n + m, 1, n + m < vci_large_system)
    allocate (self%fjac(nf, nf), self%flu(nf, nf), self%fr(n + m), self%fsc(n + m), &
              self%frt(n + m), self%fsct(n + m), self%fxt(n + m), self%fdx(n + m), self%frw(n + m), &
              self%fx0(n + m), self%fpiv(n + m), stat=stat)
    if (stat /= 0) return
    self%fjac = 0.0_dp
    ! with a declared band (no debug check) the large systems' Jacobians are written in band storage
    ! (step_band_jacobian) and a retraction's mixed Hessian straight into it: |J| and the mixed
    ! Hessian are n x n only for the small systems (below vci_large_system) or a user's L_d, whose
    ! mixed_hessian callback is dense
    nj = nx; nh = n
    if ((model%hessian_bandwidth >= 0 .and. .not. model%check_bandwidth) .or. &
        (model%hessian_pattern%n == n .and. model%hessian_bandwidth < 0 .and. .not. model%check_pattern)) then
      ! (likewise with a declared sparse pattern: step_sparse_jacobian writes in the pattern)
      nj = min(nx, vci_large_system)
      if (self%increments .and. n + m >= vci_large_system) nh = 1
    end if
    allocate (self%cjo(m, n), self%sizes(nx), self%gg1(n), self%fcol(nx), &
              self%d1(n), self%hess(nh, nh), self%g(max(1, model%n_gaps)), self%bb(n), self%start_key(n), self%start_lo(n), &
              self%end_key(n), self%end_lo(n), self%kin(n), &
              self%rp(nx), self%rm(nx), self%sp(nx), self%sm(nx), self%xp(nx), self%jscale(nx), &
              self%jabs(nj, nj), self%lkey(2, n), self%ld1(n), self%ld2(n), self%lhess(nh, nh), &
              self%jscale_kept(nx), self%kin_kept(n), self%jabs_kept(nf + 1, nf + 1), stat=stat)
    if (stat /= 0) return
    self%l_known = .false.
    self%jscale = 0.0_dp
    self%jabs = 0.0_dp
    self%jac_known = .false.
    self%have_end = .false.
    self%start_key = huge(1.0_dp); self%start_lo = 0.0_dp
    self%end_key = huge(1.0_dp); self%end_lo = 0.0_dp   ! read (before have_end is known) by get_endpoint
  end subroutine setup

  pure integer function unknowns(self, kind)
    class(vci_scheme_discrete_t), intent(in) :: self
    integer, intent(in) :: kind
    select case (kind)
    case (KIND_SUBSTEP, KIND_PAIR); unknowns = self%n + self%m
    case (KIND_IMPULSE); unknowns = self%m + 1
    case default; unknowns = self%n + self%m + 1
    end select
  end function unknowns

  subroutine put_endpoint(self, x, a, b)
    class(vci_scheme_discrete_t), intent(in) :: self
    real(dp), intent(inout) :: x(:)
    real(dp), intent(in) :: a(:), b(:)
    if (self%increments) then
      x(1:self%n) = b - a
    else
      x(1:self%n) = b
    end if
  end subroutine put_endpoint

  !> The endpoint of x. For increments, b = a + d from the sub-step's start a set by the stepper,
  !> summed with compensation: when a is an endpoint this procedure returned, the part of it that
  !> rounding dropped is added back to the increment, and the new rounding error is kept (TwoSum).
  !> Positions then carry one rounding instead of one per step (docs/bench/roundoff.md).
  subroutine get_endpoint(self, x, v)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    real(dp), intent(out) :: v(:)
    integer :: i, n
    real(dp) :: s, bv
    n = self%n
    if (.not. self%increments) then
      v = x(1:n)
      return
    end if
    if (.not. all(self%a == self%start_key)) then
      if (self%have_end .and. all(self%a == self%end_key)) then   ! the last endpoint starts this sub-step
        self%start_lo = self%end_lo
      else                                                        ! a point from elsewhere: no low part
        self%start_lo = 0.0_dp
      end if
      self%start_key = self%a
    end if
    do i = 1, n
      s = x(i) + self%start_lo(i)
      v(i) = self%a(i) + s
      bv = v(i) - self%a(i)
      self%end_lo(i) = (self%a(i) - (v(i) - bv)) + (s - bv)     ! TwoSum: a + s = v + end_lo exactly
    end do
    self%end_key = v
    self%have_end = .true.
  end subroutine get_endpoint

  !> The endpoint's part of a change of the unknowns (a sensitivity), both layouts.
  subroutine endpoint_direction(self, x, v)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    real(dp), intent(out) :: v(:)
    v = x(1:self%n)
  end subroutine endpoint_direction

  !> The endpoint b of the unknowns x into bb (both layouts).
  subroutine endpoint_of(self, x)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    if (self%increments) then
      self%bb = self%a + x(1:self%n)
    else
      self%bb = x(1:self%n)
    end if
  end subroutine endpoint_of

  !> |b - a| for the row sizes, both layouts.
  pure real(dp) function motion(self, x, j)
    class(vci_scheme_discrete_t), intent(in) :: self
    real(dp), intent(in) :: x(:)
    integer, intent(in) :: j
    if (self%increments) then
      motion = abs(x(j))
    else
      motion = abs(x(j) - self%a(j))
    end if
  end function motion

  subroutine put_multipliers(self, x, v)
    class(vci_scheme_discrete_t), intent(in) :: self
    real(dp), intent(inout) :: x(:)
    real(dp), intent(in) :: v(:)
    if (self%m > 0) x(self%n + 1:self%n + self%m) = v
  end subroutine put_multipliers

  subroutine get_multipliers(self, x, v)
    class(vci_scheme_discrete_t), intent(in) :: self
    real(dp), intent(in) :: x(:)
    real(dp), intent(out) :: v(:)
    if (self%m > 0) v = x(self%n + 1:self%n + self%m)
  end subroutine get_multipliers

  subroutine momentum_rhs(self, v, rhs)
    class(vci_scheme_discrete_t), intent(in) :: self
    real(dp), intent(in) :: v(:)
    real(dp), intent(out) :: rhs(:)
    rhs(1:self%n) = v
    rhs(self%n + 1:) = 0.0_dp
  end subroutine momentum_rhs

  !> Sub-step length at the unknowns x.
  pure real(dp) function step_length(self, x)
    class(vci_scheme_discrete_t), intent(in) :: self
    real(dp), intent(in) :: x(:)
    step_length = self%tau
    if (self%kind == KIND_STAGE1) step_length = x(self%n + self%m + 1) * self%tau
  end function step_length

  !> out = s D1 L^s(a, b, tau)  (forward: D1 L_d(a, b); backward: -D2 L_d(b, a)); b (or the
  !> increment, for retractions) is x(1:n).
  subroutine d1s(self, a, b, tau, out, stat)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: a(:), b(:), tau
    real(dp), intent(out) :: out(:)
    integer, intent(out) :: stat
    stat = 0
    if (self%increments) then
      call self%ret%d1s_inc(a, b, tau, self%dir, out, stat)
    else if (self%has_fused .and. self%dir > 0) then
      call ld_at(self, a, b, tau, stat)
      out = self%ld1
    else if (self%has_fused) then
      call ld_at(self, b, a, tau, stat)
      out = -self%ld2
    else if (self%dir > 0) then
      call self%model%d1(a, b, tau, out, stat)
    else
      call self%model%d2(b, a, tau, out, stat)
      out = -out
    end if
    call check_fast(self, stat, out, 'D1/D2 of L_d')
  end subroutine d1s

  !> A callback's status (nonzero: VCI_ERR_CALLBACK); its values are scanned only when scan_values.
  subroutine check_fast(self, stat, values, what)
    class(vci_scheme_discrete_t), intent(inout) :: self
    integer, intent(inout) :: stat
    real(dp), intent(in) :: values(:)
    character(len=*), intent(in) :: what
    if (self%scan_values .or. stat /= 0) then
      call self%check(stat, values, what)
    else
      stat = VCI_OK
    end if
  end subroutine check_fast

  !> p_b = s D2 L^s(a, b, tau)  (forward: D2 L_d(a, b); backward: -D1 L_d(b, a)), b = endpoint of x;
  !> for a retraction, from the impulse when the caller gives the momentum pa that x balances (the
  !> same value in exact arithmetic).
  subroutine momentum_out(self, x, a, tau, p, stat, pa)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), a(:), tau
    real(dp), intent(out) :: p(:)
    integer, intent(out) :: stat
    real(dp), intent(in), optional :: pa(:)
    logical :: balanced
    stat = 0
    if (self%increments) then
      balanced = present(pa)
      if (balanced) balanced = all(a == self%a)   ! Omega(a) is the posed one (no short-circuit .and.)
      if (balanced) then
        ! x balances pa: p_b = pa - Omega(a) lambda + the force impulse. D2 L_d alone is a difference
        ! of kinetic terms M d / tau, whose rounding had a mean: over 1e7 steps it grew the ellipse's
        ! energy error like t^0.8 (docs/bench/roundoff.md)
        call self%ret%impulse_inc(a, x(1:self%n), tau, self%dir, p, stat)
        call add_balance(self, x, pa, p)
      else
        call self%ret%pout_inc(a, x(1:self%n), tau, self%dir, p, stat)
      end if
    else if (self%has_fused .and. self%dir > 0) then
      call ld_at(self, a, x(1:self%n), tau, stat)
      p = self%ld2
    else if (self%has_fused) then
      call ld_at(self, x(1:self%n), a, tau, stat)
      p = -self%ld1
    else if (self%dir > 0) then
      call self%model%d2(a, x(1:self%n), tau, p, stat)
    else
      call self%model%d1(x(1:self%n), a, tau, p, stat)
      p = -p
    end if
    call self%check(stat, p, 'D1/D2 of L_d')
  end subroutine momentum_out

  !> The momentum at the end of a sub-step of an impact step (stage 1's arrival, the sub-step that
  !> leaves the wall), x balancing pa. A user's L_d: p_b = pa - Omega(a) lambda + (s D1 L^s + s D2 L^s),
  !> where the kinetic terms +-M (b - a) / tau cancel and with them b's rounding, which s D2 L^s alone
  !> carries divided by the sub-step alpha tau or (1 - alpha) tau: on the ellipse (x ~ 2e5 after
  !> 1e5 s) H jumped by ~v ulp(x) / sub-step, up to 9e-4 (tools/impact_energy). Regular steps keep
  !> s D2 L^s: it agrees with the rounded positions, so the next predictor starts at round-off (with
  !> the impulse there Newton iterated 50 % more). Retractions: momentum_out's impulse already.
  subroutine impact_momentum(self, x, a, tau, p, stat, pa)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), a(:), tau
    real(dp), intent(out) :: p(:)
    integer, intent(out) :: stat
    real(dp), intent(in), optional :: pa(:)
    call impact_momentum_balanced(self, x, a, tau, p, stat, pa)
    ! With constraints and the hamiltonian condition: the admissible part of the momentum (issue 25).
    ! D2 L_d is off the constraint manifold by O(h), and its Omega-part adds kinetic energy that no
    ! motion has: H(qt, p-) of it exceeds the energy of the motion, and H(qt, p+) = H(qt, p-) put the
    ! excess into the motion at every impact (always upward). The Omega(b)-part is no motion: the
    ! leaving sub-step's multiplier absorbs it, so positions are unchanged by this projection.
    if (stat /= VCI_OK .or. self%m == 0 .or. self%impact_energy /= VCI_IMPACT_HAMILTONIAN) return
    if (self%increments) then
      self%bb = a + x(1:self%n)
    else
      self%bb = x(1:self%n)
    end if
    call self%project_momentum(self%bb, p, stat)
  end subroutine impact_momentum

  subroutine impact_momentum_balanced(self, x, a, tau, p, stat, pa)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), a(:), tau
    real(dp), intent(out) :: p(:)
    integer, intent(out) :: stat
    real(dp), intent(in), optional :: pa(:)
    integer :: i
    call self%momentum_out(x, a, tau, p, stat, pa)
    if (stat /= VCI_OK .or. self%increments .or. .not. present(pa)) return
    if (.not. all(a == self%a)) return   ! Omega(a) is the posed one
    call d1s(self, a, x(1:self%n), tau, self%d1, stat)
    if (stat /= VCI_OK) return
    do i = 1, self%n
      p(i) = self%d1(i) + p(i)
    end do
    call add_balance(self, x, pa, p)
    call self%check(stat, p, 'D1/D2 of L_d')
  end subroutine impact_momentum_balanced

  !> p := pa + p - Omega(a) lambda (lambda from x): the momentum from the terms x's rows balance.
  subroutine add_balance(self, x, pa, p)
    class(vci_scheme_discrete_t), intent(in) :: self
    real(dp), intent(in) :: x(:), pa(:)
    real(dp), intent(inout) :: p(:)
    integer :: i, mu
    do i = 1, self%n
      p(i) = pa(i) + p(i)
      do mu = 1, self%m
        p(i) = p(i) - self%omega(i, mu) * x(self%n + mu)
      end do
    end do
  end subroutine add_balance

  !> Discrete energy E_d = -D3 L_d of the segment between a and the endpoint of x (both directions).
  subroutine energy_out(self, x, a, tau, e, stat)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), a(:), tau
    real(dp), intent(out) :: e
    integer, intent(out) :: stat
    real(dp) :: tmp(1)
    stat = 0
    if (self%increments) then
      call self%ret%energy_inc(a, x(1:self%n), tau, self%dir, e, stat)
      e = -e
    else if (self%has_fused .and. self%dir > 0) then
      call ld_at(self, a, x(1:self%n), tau, stat)
      e = self%ld3
    else if (self%has_fused) then
      call ld_at(self, x(1:self%n), a, tau, stat)
      e = self%ld3
    else if (self%dir > 0) then
      call self%model%d3(a, x(1:self%n), tau, e, stat)
    else
      call self%model%d3(x(1:self%n), a, tau, e, stat)
    end if
    e = -e
    tmp(1) = e
    call self%check(stat, tmp, 'D3 of L_d')
  end subroutine energy_out

  subroutine hamiltonian(self, q, p, e, stat)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(out) :: stat
    real(dp) :: tmp(1)
    stat = 0
    call self%model%energy(q, p, e, stat)
    tmp(1) = e
    call self%check(stat, tmp, 'energy H(q,p)')
  end subroutine hamiltonian

  !> Residual rows; with `momentum_rows` false only the constraint and last rows are evaluated
  !> (used to difference those rows when the momentum block comes from the analytic Hessian);
  !> with `gap_row` false stage 1's gap row is left out (r = 0 there: differences along alpha,
  !> on which g_j(b) does not depend).
  subroutine rows(self, x, r, sc, momentum_rows, stat, gap_row)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    real(dp), intent(out) :: r(:), sc(:)
    logical, intent(in) :: momentum_rows
    integer, intent(out) :: stat
    logical, intent(in), optional :: gap_row
    integer :: n, m, mu, last, i
    real(dp) :: tau, e, hp, ol
    n = self%n; m = self%m; last = n + m + 1
    tau = step_length(self, x)
    stat = VCI_OK
    if (momentum_rows) then
      call d1s(self, self%a, x(1:n), tau, self%d1, stat)
      if (stat /= VCI_OK) return
      call momentum_terms(n, m, self%d1, self%pa, self%omega, x(n + 1:n + m), r, sc)   ! - Omega lambda included
      if (self%kind == KIND_STAGE2) then
        r(1:n) = r(1:n) + x(last) * self%grad
        sc(1:n) = sc(1:n) + abs(x(last) * self%grad)
      end if
    end if
    if (m > 0) then
      call constraint_values(self, x(1:n), tau, r(n + 1:n + m), stat)
      call check_fast(self, stat, r(n + 1:n + m), 'discrete constraint')
      if (stat /= VCI_OK) return
      do mu = 1, m
        ol = 0.0_dp
        do i = 1, n
          ol = ol + abs(self%omega(i, mu)) * motion(self, x, i)
        end do
        sc(n + mu) = abs(r(n + mu)) + ol / tau
      end do
    end if
    select case (self%kind)
    case (KIND_STAGE1)
      if (present(gap_row)) then
        if (.not. gap_row) then
          r(last) = 0.0_dp; sc(last) = 1.0_dp; return
        end if
      end if
      call endpoint_of(self, x)
      call self%eval_gaps(self%bb, self%g(1:self%n_gaps), stat)
      if (stat /= VCI_OK) return
      r(last) = self%g(self%gap)
      ! g's size: its value, its terms (grad g . q) and its change over the sub-step; and |grad g|
      ! times the sub-step's largest motion in any coordinate: a hop from a wall at coordinate 0
      ! back to it has value, terms and normal change all ~0 at the root (reversal seed 126: a
      ! scale of 2e-34, which Newton's line search could not meet)
      ol = 0.0_dp; e = 0.0_dp
      do i = 1, n
        ol = ol + self%gscale(i) * (abs(self%bb(i)) + motion(self, x, i))
        e = max(e, motion(self, x, i))
      end do
      sc(last) = abs(r(last)) + ol + sum(self%gscale) * e
    case (KIND_STAGE2)
      if (self%impact_energy == VCI_IMPACT_HAMILTONIAN) then
        self%pplus = self%pa + x(last) * self%grad
        call self%hamiltonian(self%a, self%pplus, hp, stat)
        if (stat /= VCI_OK) return
        r(last) = hp - self%e_minus
        sc(last) = abs(hp) + abs(self%e_minus)
      else
        call self%energy_out(x, self%a, tau, e, stat)
        if (stat /= VCI_OK) return
        r(last) = e - self%e_minus
        sc(last) = abs(e) + abs(self%e_minus)
      end if
      ol = 0.0_dp
      do i = 1, n
        ol = ol + abs(self%pa(i)) * motion(self, x, i)
      end do
      sc(last) = sc(last) + ol / tau
    end select
  end subroutine rows

  subroutine step_residual(self, x, r, scale, stat)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    real(dp), intent(out) :: r(:), scale(:)
    integer, intent(out) :: stat
    integer :: j, n
    real(dp) :: fl
    n = self%n
    call rows(self, x, r, scale, .true., stat)
    if (stat /= VCI_OK) return
    ! size of the kinetic terms of the momentum rows, from the current solve's Jacobian (large
    ! systems: taken at that Jacobian's point), and the round-off floor of each row: a few ulps of
    ! sum_j |dR_i/dx_j| |x_j|, in units of rtol
    fl = 8.0_dp * epsilon(1.0_dp) / max(self%rtol, epsilon(1.0_dp))
    if (self%jac_known .and. size(x) >= vci_large_system) then
      scale(1:n) = scale(1:n) + self%kin
    else if (self%jac_known) then
      do j = 1, n
        self%kin(j) = motion(self, x, j)
      end do
    end if
    call kinetic_and_floor(n, size(x), size(self%jabs, 1), self%jabs, self%kin, &
                           self%jac_known .and. size(x) < vci_large_system, fl, self%jscale, scale)
    ! one finiteness check for all the callbacks' values; when it fails, evaluate again scanning
    ! each callback's values so that the failure names the culprit
    if (.not. ieee_is_finite(sum(r) + sum(scale))) then
      self%scan_values = .true.
      call rows(self, x, r, scale, .true., stat)
      self%scan_values = .false.
    end if
  end subroutine step_residual

  !> Jacobian: the momentum block from the model's mixed Hessian when it has one, the constraint
  !> rows from the model's constraint Jacobian when it has one (the left retraction's are linear),
  !> multiplier and impulse columns analytically, everything else by central differences.
  subroutine step_jacobian(self, x, r, jac, stat)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), r(:)
    real(dp), intent(inout) :: jac(:, :)
    integer, intent(out) :: stat
    integer :: n, nx, i, j, nb, bw
    real(dp) :: tau
    logical :: chk
    n = self%n; nx = size(x)
    stat = VCI_OK
    tau = step_length(self, x)
    ! columns of b
    if (self%has_hessian) then
      call momentum_block(self, x, tau, jac, stat)
      if (stat /= VCI_OK) return
      ! no differenced columns of b where the rows are known: border_rows
      call border_rows(self, x, tau, jac(n + 1:nx, 1:n), stat)
      if (stat /= VCI_OK) return
    else
      do j = 1, n
        call fd_column(self, x, j, fd_step(position(self, x, j), motion(self, x, j)), .true., jac(:, j), stat)
        if (stat /= VCI_OK) return
      end do
    end if
    ! multiplier columns and stage 1's alpha or stage 2's mu column
    call border_columns(self, x, jac(1:nx, n + 1:nx), stat)
    ! |J| for the kinetic term of the momentum rows, and the round-off floor sum_j |J_ij| |x_j|, sized on
    ! positions in both layouts (a user's L_d rounds b - a to ulps of |b|; a retraction rounds
    ! a + d/2 where forces are evaluated); explicit loops: array syntax on these sections costs more
    ! than the arithmetic at small n
    do j = 1, nx
      if (j <= n) then
        self%sizes(j) = abs(position(self, x, j))
      else
        self%sizes(j) = abs(x(j))
      end if
    end do
    call banded_structure(self, nb, bw, chk)
    if (nb > 0 .and. .not. chk) then
      ! the band of the position block and the border only (the rest is zero, and not written in
      ! Newton's matrix; jabs keeps its zeros there from setup): O(n bw)
      call band_jacobian_sizes(nx, nb, bw, jac, self%sizes, size(self%jabs, 1), self%jabs, self%jscale)
      self%jac_known = .true.
      if (nx < vci_large_system) return
      self%kin = 0.0_dp
      do j = 1, n
        do i = max(1, j - bw), min(n, j + bw)
          self%kin(i) = self%kin(i) + self%jabs(i, j) * motion(self, x, j)
        end do
      end do
      return
    end if
    call jacobian_sizes(nx, jac, self%sizes, size(self%jabs, 1), self%jabs, self%jscale)
    self%jac_known = .true.
    if (nx >= vci_large_system) then
      self%kin = 0.0_dp
      do j = 1, n
        self%kin = self%kin + self%jabs(1:n, j) * motion(self, x, j)
      end do
    end if
  end subroutine step_jacobian

  !> Is the last row of stage 1 or 2 known in closed form along b? Stage 1's g_j(b): its gradient
  !> (the model's, else eval_gap_gradients' differences of g alone). Stage 2 with the Hamiltonian
  !> condition H(qt, p- + mu grad g) = H(qt, p-): free of b. (Stage 2's E_d row stays differenced.)
  pure logical function analytic_last_row(self)
    class(vci_scheme_discrete_t), intent(in) :: self
    analytic_last_row = self%kind == KIND_STAGE1 .or. &
                        (self%kind == KIND_STAGE2 .and. self%impact_energy == VCI_IMPACT_HAMILTONIAN)
  end function analytic_last_row

  !> jac(1:n, 1:n) = d(s D1 L^s)/db from the model's mixed Hessian (its transpose, negated, backward).
  subroutine momentum_block(self, x, tau, jac, stat)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), tau
    real(dp), intent(inout) :: jac(:, :)
    integer, intent(out) :: stat
    integer :: i, j, n, nb, bw
    logical :: chk
    n = self%n
    stat = 0
    call banded_structure(self, nb, bw, chk)
    if (nb > 0 .and. .not. chk .and. self%increments) then
      ! straight into the band of Newton's matrix, checked there: O(n bw)
      call self%ret%jacobian_inc(self%a, x(1:n), tau, self%dir, jac(1:n, 1:n), stat)
      call self%check_band(stat, jac(1:n, 1:n), bw, 'mixed Hessian')
      return
    end if
    if (self%increments) then
      call self%ret%jacobian_inc(self%a, x(1:n), tau, self%dir, self%hess, stat)
    else
      call user_mixed_hessian(self, x(1:n), tau, stat)
    end if
    if (nb > 0 .and. .not. chk) then        ! a user's L_d: its dense Hessian, read on the band
      call self%check_band(stat, self%hess, bw, 'mixed Hessian')
      if (stat /= VCI_OK) return
      do j = 1, n
        do i = max(1, j - bw), min(n, j + bw)
          if (self%dir > 0) then
            jac(i, j) = self%hess(i, j)
          else
            jac(i, j) = -self%hess(j, i)
          end if
        end do
      end do
      return
    end if
    call self%check_matrix(stat, self%hess, 'mixed Hessian')
    if (stat /= VCI_OK) return
    if (self%increments .or. self%dir > 0) then
      do j = 1, n
        do i = 1, n
          jac(i, j) = self%hess(i, j)
        end do
      end do
    else
      do j = 1, n
        do i = 1, n
          jac(i, j) = -self%hess(j, i)
        end do
      end do
    end if
  end subroutine momentum_block

  !> The sub-step's constraint rows jac(n+1:n+m, 1:n) = d omega_d(a, b) / db: from the model's
  !> Jacobian along `other`, the left retraction's Omega(a)^T / tau, or central differences.
  subroutine constraint_block(self, x, tau, jac, stat)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), tau
    real(dp), intent(inout) :: jac(:, :)
    integer, intent(out) :: stat
    call constraint_rows(self, x, tau, jac(self%n + 1:self%n + self%m, 1:self%n), stat)
  end subroutine constraint_block

  !> constraint_block's rows into cb(1:m, 1:n) (the rows alone: a matrix in band storage keeps its
  !> border rows apart, vci_banded_matrix).
  subroutine constraint_rows(self, x, tau, cb, stat)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), tau
    real(dp), intent(inout) :: cb(:, :)
    integer, intent(out) :: stat
    integer :: i, j, n, m
    n = self%n; m = self%m
    stat = VCI_OK
    if (self%increments) then
      if (self%ret%rule == RETRACTION_LEFT) then
        ! left retraction: omega_d = Omega(a)^T d / tau is linear in d
        do j = 1, n
          do i = 1, m
            cb(i, j) = self%omega(j, i) / tau
          end do
        end do
        return
      end if
    else if (self%has_constraint_jacobian) then
      ! both directions impose omega_d(a, b): the known point is the base (DESIGN.md §1)
      stat = 0
      call self%model%discrete_constraint_jacobian(self%a, x(1:n), tau, self%cjo, stat)
      call self%check_matrix(stat, self%cjo, 'discrete constraint Jacobian')
      if (stat /= VCI_OK) return
      cb(1:m, 1:n) = self%cjo
      return
    end if
    do j = 1, n
      call fd_constraint_column(self, x, j, tau, fd_step(position(self, x, j), motion(self, x, j)), &
                                cb(1:m, j), stat)
      if (stat /= VCI_OK) return
    end do
  end subroutine constraint_rows

  !> Does the posed system write its Jacobian in band storage (step_band_jacobian)? With a declared
  !> band, no debug check, and vci_large_system unknowns or more (smaller systems keep the n x n
  !> path: it is small, and the fused solve and the kinetic sizes read it densely).
  logical function discrete_packs_band(self)
    class(vci_scheme_discrete_t), intent(inout) :: self
    integer :: nb, bw
    logical :: chk
    call banded_structure(self, nb, bw, chk)
    discrete_packs_band = nb > 0 .and. .not. chk .and. self%unknowns(self%kind) >= vci_large_system
  end function discrete_packs_band

  !> step_jacobian written in the declared structure (vci_banded_matrix; posed and zeroed by
  !> Newton): the band of the position block, the constraint, gap or energy rows and the
  !> multiplier and alpha or mu columns apart. The same entries as step_jacobian's on the band
  !> (a differenced column's entries outside the band are zero by declaration and dropped), and
  !> the same row sizes (jscale, kin); nothing of size n^2.
  subroutine step_band_jacobian(self, x, r, mat, stat)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), r(:)
    type(vci_band_matrix_t), intent(inout) :: mat
    integer, intent(out) :: stat
    integer :: n, nx, i, j, k, bw
    real(dp) :: tau, hp, t
    n = self%n; nx = size(x)
    bw = mat%bw; k = bw + 1
    stat = VCI_OK
    tau = step_length(self, x)
    ! columns of b
    if (self%has_hessian) then
      call momentum_band(self, x, tau, mat, stat)
      if (stat /= VCI_OK) return
      call border_rows(self, x, tau, mat%rows, stat)
    else
      do j = 1, n
        call fd_column(self, x, j, fd_step(position(self, x, j), motion(self, x, j)), .true., self%fcol(1:nx), stat)
        if (stat /= VCI_OK) return
        do i = max(1, j - bw), min(n, j + bw)
          mat%band(k + i - j, j) = self%fcol(i)
        end do
        mat%rows(1:nx - n, j) = self%fcol(n + 1:nx)
      end do
    end if
    if (stat /= VCI_OK) return
    call border_columns(self, x, mat%cols, stat)
    if (stat /= VCI_OK) return
    ! the row sizes of step_jacobian: jscale(i) = sum_j |J_ij| size_j, kin(i) = sum_j |J_ij| motion_j
    ! over the position block (its band), then the border's
    call start_row_sizes(self, x)
    do j = 1, n
      hp = motion(self, x, j)
      do i = max(1, j - bw), min(n, j + bw)
        t = abs(mat%band(k + i - j, j))
        self%jscale(i) = self%jscale(i) + t * self%sizes(j)
        self%kin(i) = self%kin(i) + t * hp
      end do
    end do
    call border_row_sizes(self, x, mat%rows, mat%cols)
    self%jac_known = .true.
  end subroutine step_band_jacobian

  !> Does the posed system write its Jacobian in the declared sparse pattern (step_sparse_jacobian)?
  !> With a declared pattern, no debug check, and vci_large_system unknowns or more (smaller systems
  !> keep the n x n path, as for the band).
  logical function discrete_packs_sparse(self)
    class(vci_scheme_discrete_t), intent(inout) :: self
    integer :: nb
    logical :: chk
    type(vci_sparse_pattern_t), pointer :: pat
    call declared_pattern(self, nb, pat, chk)
    discrete_packs_sparse = nb > 0 .and. .not. chk .and. self%unknowns(self%kind) >= vci_large_system
  end function discrete_packs_sparse

  !> step_band_jacobian in the declared sparse pattern (vci_sparse_matrix; posed and zeroed by
  !> Newton): the pattern's values of the position block, the constraint, gap or energy rows and
  !> the multiplier and alpha or mu columns apart. The same entries as step_jacobian's in the
  !> pattern (a differenced column's entries outside it are zero by declaration and dropped), the
  !> same row sizes (jscale, kin); nothing of size n^2 unless a user's L_d gives its dense mixed
  !> Hessian (read in the pattern).
  subroutine step_sparse_jacobian(self, x, r, mat, stat)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), r(:)
    type(vci_sparse_matrix_t), intent(inout) :: mat
    integer, intent(out) :: stat
    integer :: n, nx, i, j, k
    real(dp) :: tau, hp, t
    n = self%n; nx = size(x)
    stat = VCI_OK
    tau = step_length(self, x)
    associate (pat => mat%pat)
      ! columns of b
      if (self%has_hessian) then
        call momentum_sparse(self, x, tau, mat, stat)
        if (stat /= VCI_OK) return
        call border_rows(self, x, tau, mat%rows, stat)
      else
        do j = 1, n
          call fd_column(self, x, j, fd_step(position(self, x, j), motion(self, x, j)), .true., self%fcol(1:nx), stat)
          if (stat /= VCI_OK) return
          do k = pat%colptr(j), pat%colptr(j + 1) - 1
            mat%val(k) = self%fcol(pat%rowind(k))
          end do
          mat%rows(1:nx - n, j) = self%fcol(n + 1:nx)
        end do
      end if
      if (stat /= VCI_OK) return
      call border_columns(self, x, mat%cols, stat)
      if (stat /= VCI_OK) return
      ! the row sizes of step_jacobian over the position block's pattern, then the border's
      call start_row_sizes(self, x)
      do j = 1, n
        hp = motion(self, x, j)
        do k = pat%colptr(j), pat%colptr(j + 1) - 1
          i = pat%rowind(k)
          t = abs(mat%val(k))
          self%jscale(i) = self%jscale(i) + t * self%sizes(j)
          self%kin(i) = self%kin(i) + t * hp
        end do
      end do
      call border_row_sizes(self, x, mat%rows, mat%cols)
    end associate
    self%jac_known = .true.
  end subroutine step_sparse_jacobian

  !> The border rows of a structured Jacobian (band or pattern) from analytic Hessians: the
  !> constraint rows, stage 1's gap row, or (no analytic last row) the differenced rows of every
  !> position column. rows(i, j): row n + i, column j.
  subroutine border_rows(self, x, tau, rows, stat)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), tau
    real(dp), intent(inout) :: rows(:, :)
    integer, intent(out) :: stat
    integer :: n, m, nx, nd, j
    n = self%n; m = self%m; nx = size(x); nd = nx - n
    stat = VCI_OK
    if (nx > n .and. self%kind == KIND_SUBSTEP) then
      if (m > 0) call constraint_rows(self, x, tau, rows(1:m, 1:n), stat)
    else if (nx > n .and. analytic_last_row(self)) then
      if (m > 0) call constraint_rows(self, x, tau, rows(1:m, 1:n), stat)
      if (stat /= VCI_OK) return
      if (self%kind == KIND_STAGE1) then
        call endpoint_of(self, x)
        call self%eval_gap_gradient(self%bb, self%gap, self%gg1, stat)
        if (stat /= VCI_OK) return
        rows(nd, 1:n) = self%gg1
      end if
    else if (nx > n) then
      do j = 1, n
        call fd_column(self, x, j, fd_step(position(self, x, j), motion(self, x, j)), .false., self%fcol(1:nx), stat)
        if (stat /= VCI_OK) return
        rows(1:nd, j) = self%fcol(n + 1:nx)
      end do
    end if
  end subroutine border_rows

  !> The border columns of a structured Jacobian: d/d lambda of -Omega(a) lambda, then stage 1's
  !> alpha column (differenced) or stage 2's mu column. cols(i, j): row i, column n + j.
  subroutine border_columns(self, x, cols, stat)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    real(dp), intent(inout) :: cols(:, :)
    integer, intent(out) :: stat
    integer :: n, m, nx, nd, last, i, j
    real(dp) :: d
    n = self%n; m = self%m; nx = size(x); nd = nx - n; last = n + m + 1
    stat = VCI_OK
    do j = 1, m
      do i = 1, n
        cols(i, j) = -self%omega(i, j)
      end do
    end do
    select case (self%kind)
    case (KIND_STAGE1)       ! alpha enters through the sub-step length; g_j(b) does not depend on it
      d = vci_fd_rel * x(last)
      call fd_column(self, x, last, d, .true., cols(1:nx, nd), stat, gap_row=.false.)
      cols(last, nd) = 0.0_dp
    case (KIND_STAGE2)    ! mu enters linearly in the momentum rows
      cols(1:n, nd) = self%grad
      if (self%impact_energy == VCI_IMPACT_HAMILTONIAN) then
        call hamiltonian_mu_slope(self, x(last), cols(last, nd), stat)
      end if
    end select
  end subroutine border_columns

  !> The unknowns' sizes and the row sizes (jscale, kin) set to zero, before a structured
  !> Jacobian's block adds its part.
  subroutine start_row_sizes(self, x)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    integer :: j
    do j = 1, size(x)
      if (j <= self%n) then
        self%sizes(j) = abs(position(self, x, j))
      else
        self%sizes(j) = abs(x(j))
      end if
    end do
    self%jscale(1:size(x)) = 0.0_dp
    self%kin = 0.0_dp
  end subroutine start_row_sizes

  !> The border's part of the row sizes of step_jacobian (rows n+1.., then every row's border columns).
  subroutine border_row_sizes(self, x, rows, cols)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), rows(:, :), cols(:, :)
    integer :: n, nx, nd, i, j
    n = self%n; nx = size(x); nd = nx - n
    do j = 1, n
      do i = 1, nd
        self%jscale(n + i) = self%jscale(n + i) + abs(rows(i, j)) * self%sizes(j)
      end do
    end do
    do j = 1, nd
      do i = 1, nx
        self%jscale(i) = self%jscale(i) + abs(cols(i, j)) * self%sizes(n + j)
      end do
    end do
  end subroutine border_row_sizes

  !> momentum_block into the sparse pattern: a retraction's mixed Hessian written there by its own
  !> routine (from the model's sparse Hessians, or its dense ones read in the pattern); a user's
  !> L_d's dense mixed Hessian (its callback's shape) read in the pattern.
  subroutine momentum_sparse(self, x, tau, mat, stat)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), tau
    type(vci_sparse_matrix_t), intent(inout) :: mat
    integer, intent(out) :: stat
    integer :: i, j, k, n
    n = self%n
    stat = 0
    if (self%increments) then
      call self%ret%jacobian_inc_sparse(self%a, x(1:n), tau, self%dir, mat%pat, mat%val, stat)
      call self%check(stat, mat%val, 'mixed Hessian')
      return
    end if
    call user_mixed_hessian(self, x(1:n), tau, stat)
    call self%check_matrix(stat, self%hess, 'mixed Hessian')
    if (stat /= VCI_OK) return
    do j = 1, n
      do k = mat%pat%colptr(j), mat%pat%colptr(j + 1) - 1
        i = mat%pat%rowind(k)
        if (self%dir > 0) then
          mat%val(k) = self%hess(i, j)
        else
          mat%val(k) = -self%hess(j, i)
        end if
      end do
    end do
  end subroutine momentum_sparse

  !> slope = d/dmu H(a, pa + mu grad) by a central difference (stage 2's Hamiltonian row).
  subroutine hamiltonian_mu_slope(self, mu, slope, stat)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: mu
    real(dp), intent(inout) :: slope
    integer, intent(inout) :: stat
    real(dp) :: d, hp, hm
    d = vci_fd_rel * max(abs(mu), sqrt(sum(self%pa**2)) / max(sqrt(sum(self%grad**2)), tiny(1.0_dp)))
    self%pplus = self%pa + (mu + d) * self%grad
    call self%hamiltonian(self%a, self%pplus, hp, stat)
    if (stat /= VCI_OK) return
    self%pplus = self%pa + (mu - d) * self%grad
    call self%hamiltonian(self%a, self%pplus, hm, stat)
    if (stat /= VCI_OK) return
    slope = (hp - hm) / (2.0_dp * d)
  end subroutine hamiltonian_mu_slope

  !> self%hess = the user's L_d's mixed Hessian at (a, b) (forward) or (b, a) (backward), from the
  !> fused callback when the model has one, else the separate one.
  subroutine user_mixed_hessian(self, b, tau, stat)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: b(:), tau
    integer, intent(inout) :: stat        !< preset to 0 by the caller (the callbacks' contract)
    if (self%has_fused) then
      if (self%dir > 0) then
        call ld_at(self, self%a, b, tau, stat)
      else
        call ld_at(self, b, self%a, tau, stat)
      end if
      self%hess = self%lhess
    else if (self%dir > 0) then
      call self%model%mixed_hessian(self%a, b, tau, self%hess, stat)
    else
      call self%model%mixed_hessian(b, self%a, tau, self%hess, stat)
    end if
  end subroutine user_mixed_hessian

  !> momentum_block into band storage: a retraction's mixed Hessian written there by its own band
  !> routine; a user's L_d's dense mixed Hessian (its callback's shape) read on the band.
  subroutine momentum_band(self, x, tau, mat, stat)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), tau
    type(vci_band_matrix_t), intent(inout) :: mat
    integer, intent(out) :: stat
    integer :: i, j, n, bw, k
    n = self%n; bw = mat%bw; k = bw + 1
    stat = 0
    if (self%increments) then
      call self%ret%jacobian_inc_band(self%a, x(1:n), tau, self%dir, mat%band, stat)
      call self%check_matrix(stat, mat%band, 'mixed Hessian')
      return
    end if
    call user_mixed_hessian(self, x(1:n), tau, stat)
    call self%check_band(stat, self%hess, bw, 'mixed Hessian')
    if (stat /= VCI_OK) return
    do j = 1, n
      do i = max(1, j - bw), min(n, j + bw)
        if (self%dir > 0) then
          mat%band(k + i - j, j) = self%hess(i, j)
        else
          mat%band(k + i - j, j) = -self%hess(j, i)
        end if
      end do
    end do
  end subroutine momentum_band

  !> A regular sub-step of length tau on the factors kept from one of length tau_old in the same
  !> direction (old_key = dir tau_old; issue 28): its momentum rows' Jacobian D2 D1 L_d is
  !> -M / tau + O(1) + O(tau) (the kinetic term of L_d = tau L(., (b - a)/tau)), so the old Newton
  !> step times tau / tau_old is the new one up to the force terms' (tau_old^2 - tau^2) share,
  !> ~ h^2 |Hessian of V| / |M| (1e-4 on the FPU chain at h = 0.01). The sub-steps inside an impact
  !> (stage 2's, the poke screen's half sub-steps, the 1e-3 departures) then take chord steps on the
  !> last factors instead of a new Jacobian each; Newton keeps a chord step only where it contracts
  !> the residual by reuse_contraction, else it factorises as before. Not with multipliers (their
  !> columns and the constraint rows do not scale with 1/tau) and not for stage systems.
  real(dp) function substep_chord_ratio(self, old_key)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: old_key
    real(dp) :: key
    substep_chord_ratio = 0.0_dp
    if (self%kind /= KIND_SUBSTEP .or. self%m > 0) return
    key = self%reuse_key()
    if (key / old_key > 0.0_dp) substep_chord_ratio = key / old_key
  end function substep_chord_ratio

  !> An impact stage's block (the unknowns before alpha or mu) is the Newton matrix of a regular
  !> sub-step: of length alpha tau for stage 1 (alpha at the solution x), tau (the rest of the
  !> sub-step) for stage 2; its key as substep_key names it. 0 with multipliers (as chord_ratio).
  real(dp) function stage_block_key(self, x)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    stage_block_key = 0.0_dp
    if (self%m > 0) return
    if (self%kind == KIND_STAGE1) stage_block_key = real(self%dir, dp) * x(size(x)) * self%tau
    if (self%kind == KIND_STAGE2) stage_block_key = real(self%dir, dp) * self%tau
  end function stage_block_key

  !> A new solve starts: its Jacobian is not known yet (see jabs).
  subroutine forget_jacobian(self)
    class(vci_scheme_discrete_t), intent(inout) :: self
    self%jac_known = .false.
    self%l_known = .false.   ! (a model changed between solves is asked again)
  end subroutine forget_jacobian

  !> The row sizes the next solve starts with (jscale: the round-off floor of every row, from the
  !> last Jacobian; jabs, kin, jac_known), kept (vci_scheme: keep_row_sizes). jabs is kept only
  !> where it is small (below vci_large_system unknowns), which is where side solves are made.
  subroutine discrete_keep_row_sizes(self)
    class(vci_scheme_discrete_t), intent(inout) :: self
    integer :: nk
    self%jscale_kept = self%jscale
    self%kin_kept = self%kin
    self%jac_known_kept = self%jac_known
    nk = min(size(self%jabs, 1), size(self%jabs_kept, 1))
    self%jabs_kept(1:nk, 1:nk) = self%jabs(1:nk, 1:nk)
  end subroutine discrete_keep_row_sizes

  !> Back to the row sizes discrete_keep_row_sizes kept.
  subroutine discrete_restore_row_sizes(self)
    class(vci_scheme_discrete_t), intent(inout) :: self
    integer :: nk
    self%jscale = self%jscale_kept
    self%kin = self%kin_kept
    self%jac_known = self%jac_known_kept
    nk = min(size(self%jabs, 1), size(self%jabs_kept, 1))
    self%jabs(1:nk, 1:nk) = self%jabs_kept(1:nk, 1:nk)
  end subroutine discrete_restore_row_sizes

  !> b_j, both layouts.
  pure real(dp) function position(self, x, j)
    class(vci_scheme_discrete_t), intent(in) :: self
    real(dp), intent(in) :: x(:)
    integer, intent(in) :: j
    if (self%increments) then
      position = self%a(j) + x(j)
    else
      position = x(j)
    end if
  end function position

  pure real(dp) function fd_step(xj, change)
    real(dp), intent(in) :: xj, change
    fd_step = vci_fd_rel * max(abs(xj), abs(change))
    if (fd_step == 0.0_dp) fd_step = vci_fd_rel
  end function fd_step

  !> out = omega_d(a, b, tau) of the posed start a, with xb = b (or the increment, for retractions);
  !> stat is the callback's own (not checked here).
  subroutine constraint_values(self, xb, tau, out, stat)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: xb(:), tau
    real(dp), intent(out) :: out(:)
    integer, intent(out) :: stat
    stat = 0
    if (self%increments) then
      call self%ret%constraint_inc(self%a, xb, tau, out, stat)
    else
      call self%model%discrete_constraint(self%a, xb, tau, out, stat)
    end if
  end subroutine constraint_values

  !> Central difference of the discrete constraint omega_d(a, b, tau) along b_j.
  subroutine fd_constraint_column(self, x, j, tau, d, col, stat)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), tau, d
    integer, intent(in) :: j
    real(dp), intent(out) :: col(:)
    integer, intent(out) :: stat
    integer :: n, m
    n = self%n; m = self%m
    self%xp(1:n) = x(1:n)
    self%xp(j) = x(j) + d
    call constraint_values(self, self%xp(1:n), tau, self%rp(1:m), stat)
    call self%check(stat, self%rp(1:m), 'discrete constraint')
    if (stat /= VCI_OK) return
    self%xp(j) = x(j) - d
    call constraint_values(self, self%xp(1:n), tau, self%rm(1:m), stat)
    call self%check(stat, self%rm(1:m), 'discrete constraint')
    if (stat /= VCI_OK) return
    col = (self%rp(1:m) - self%rm(1:m)) / (2.0_dp * d)
  end subroutine fd_constraint_column

  !> Central difference of the residual along unknown j (all rows, or only the non-momentum rows).
  subroutine fd_column(self, x, j, d, all_rows, col, stat, gap_row)
    class(vci_scheme_discrete_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    integer, intent(in) :: j
    real(dp), intent(in) :: d
    logical, intent(in) :: all_rows
    real(dp), intent(inout) :: col(:)
    integer, intent(out) :: stat
    logical, intent(in), optional :: gap_row   !< rows' gap_row
    integer :: nx, first
    nx = size(x)
    first = 1
    if (.not. all_rows) first = self%n + 1
    self%xp(1:nx) = x
    self%xp(j) = x(j) + d
    call rows(self, self%xp(1:nx), self%rp(1:nx), self%sp(1:nx), all_rows, stat, gap_row)
    if (stat /= VCI_OK) return
    self%xp(j) = x(j) - d
    call rows(self, self%xp(1:nx), self%rm(1:nx), self%sm(1:nx), all_rows, stat, gap_row)
    if (stat /= VCI_OK) return
    col(first:nx) = (self%rp(first:nx) - self%rm(first:nx)) / (2.0_dp * d)
  end subroutine fd_column
end module vci_scheme_discrete
