!> The `left` and `midpoint` schemes: discrete Lagrangians in closed form built from a continuous L by
!> a retraction (the paper's L_d = L o Psi_d), served to the discrete scheme as one more vci_model_t.
!> With w = (v - q)/h:
!>   left     : L_d = h L(q, w),             omega_d(q, v, h) = Omega(q)^T w            (order 1)
!>   midpoint : L_d = h L((q + v)/2, w),     omega_d(q, v, h) = Omega((q + v)/2)^T w    (symmetric, order 2)
!> D3 L_d = L - dL/dqdot . w, so E_d = -D3 L_d = E(point, w): the continuous energy at the segment's
!> velocity. The mixed Hessian comes from the Hessian blocks of L (the model's, or none: the discrete
!> scheme then differences D1). H(q, p) is the model's when it supplies one, else the Legendre
!> inversion of dL/dqdot (vci_lagrangian).
!>
!> Increments (DESIGN.md §6, round-off): the discrete scheme solves a retraction's sub-step for the
!> increment d = b - a from the known point a rather than for b, through the `*_inc` procedures
!> below. The velocity is then w = s d/h exactly: forming b and subtracting a again would round the
!> increment to ulps of |q|, an error the new momentum carries as eps |q| / h (it dominated long
!> fine-step runs: docs/bench/roundoff.md).
module vci_retraction
  use vci_kinds, only: dp
  use vci_status, only: VCI_OK, VCI_ERR_CALLBACK
  use vci_model, only: vci_model_t
  use vci_lagrangian, only: vci_lagrangian_t, vci_lagrangian_work_t, lagrangian_work_setup, &
                            lagrangian_hessians, lagrangian_hamiltonian, lagrangian_band_hessians, &
                            lagrangian_sparse_hessians
  use vci_sparse, only: vci_sparse_pattern_t
  implicit none
  private

  integer, parameter, public :: RETRACTION_LEFT = 1, RETRACTION_MIDPOINT = 2

  type, extends(vci_model_t), public :: vci_retraction_model_t
    class(vci_lagrangian_t), pointer :: lag => null()
    integer :: rule = RETRACTION_MIDPOINT
    logical :: has_model_energy = .false.
    !> the model's banded Hessians are used (hessians_band, with a declared bandwidth): lqq, lqv,
    !> lvv are then band storage, (2 bw + 1) x n, entry (i, j) at row bw + 1 + i - j
    logical :: band_hessians = .false.
    !> the model's sparse Hessians are used (hessians_sparse, with a declared pattern): sqq, sqv,
    !> svv hold them in the pattern's order and lqq, lqv, lvv are 1 x 1
    logical :: sparse_hessians = .false.
    real(dp), allocatable, private :: sqq(:), sqv(:), svv(:)
    type(vci_lagrangian_work_t) :: work
    real(dp), allocatable, private :: pt(:), w(:), lq(:), lv(:), lqq(:, :), lqv(:, :), lvv(:, :), om(:, :)
  contains
    procedure :: bind
    procedure :: d1, d2, d3, mixed_hessian, constraint_forms, discrete_constraint, gaps, gap_gradients, energy
    procedure :: gap_gradient
    procedure :: impulse_inc
    procedure :: d1s_inc, pout_inc, energy_inc, jacobian_inc, constraint_inc
    !> jacobian_inc into compact band storage (a declared bandwidth, no n x n array).
    procedure :: jacobian_inc_band
    !> jacobian_inc into the values of a declared sparse pattern (no n x n array).
    procedure :: jacobian_inc_sparse
  end type vci_retraction_model_t

contains

  !> Wrap lag with rule (RETRACTION_LEFT or RETRACTION_MIDPOINT); has_hessians and has_energy say
  !> which optional procedures the model supplies (probed by the integrator). stat /= 0: out of memory.
  subroutine bind(self, lag, rule, has_hessians, has_energy, stat)
    class(vci_retraction_model_t), intent(inout) :: self
    class(vci_lagrangian_t), target, intent(inout) :: lag
    integer, intent(in) :: rule
    logical, intent(in) :: has_hessians, has_energy
    integer, intent(out) :: stat
    integer :: n
    self%lag => lag
    self%rule = rule
    self%n = lag%n; self%m = lag%m; self%n_gaps = lag%n_gaps
    self%hessian_bandwidth = lag%hessian_bandwidth; self%check_bandwidth = lag%check_bandwidth
    self%hessian_pattern = lag%hessian_pattern; self%check_pattern = lag%check_pattern
    self%pattern_status = lag%pattern_status; self%pattern_message = lag%pattern_message
    n = lag%n
    self%band_hessians = .false.
    if (lag%hessian_bandwidth >= 0) then
      call probe_band_hessians(self, lag, stat)
      if (stat /= 0) return
    end if
    self%sparse_hessians = .false.
    if (lag%hessian_bandwidth < 0 .and. lag%hessian_pattern%n == n) then
      call probe_sparse_hessians(self, lag, stat)
      if (stat /= 0) return
    end if
    if (self%band_hessians) then
      call lagrangian_work_setup(self%work, n, stat, band=lag%hessian_bandwidth)
    else if (self%sparse_hessians) then
      call lagrangian_work_setup(self%work, n, stat, pattern=lag%hessian_pattern)
    else
      call lagrangian_work_setup(self%work, n, stat)
    end if
    if (stat /= 0) return
    self%work%has_hessians = has_hessians .or. self%band_hessians .or. self%sparse_hessians
    self%has_model_energy = has_energy
    ! array by array: after an allocate that failed part-way some are allocated and some not
    if (allocated(self%pt)) deallocate (self%pt)
    if (allocated(self%w)) deallocate (self%w)
    if (allocated(self%lq)) deallocate (self%lq)
    if (allocated(self%lv)) deallocate (self%lv)
    if (allocated(self%lqq)) deallocate (self%lqq)
    if (allocated(self%lqv)) deallocate (self%lqv)
    if (allocated(self%lvv)) deallocate (self%lvv)
    if (allocated(self%om)) deallocate (self%om)
    allocate (self%pt(n), self%w(n), self%lq(n), self%lv(n), self%om(n, max(1, lag%m)), stat=stat)
    if (stat /= 0) return
    if (allocated(self%sqq)) deallocate (self%sqq)
    if (allocated(self%sqv)) deallocate (self%sqv)
    if (allocated(self%svv)) deallocate (self%svv)
    if (self%band_hessians) then
      allocate (self%lqq(2 * self%hessian_bandwidth + 1, n), self%lqv(2 * self%hessian_bandwidth + 1, n), &
                self%lvv(2 * self%hessian_bandwidth + 1, n), stat=stat)
    else if (self%sparse_hessians) then
      associate (nnz => lag%hessian_pattern%colptr(n + 1) - 1)
        allocate (self%lqq(1, 1), self%lqv(1, 1), self%lvv(1, 1), self%sqq(nnz), self%sqv(nnz), self%svv(nnz), &
                  stat=stat)
      end associate
    else
      allocate (self%lqq(n, n), self%lqv(n, n), self%lvv(n, n), stat=stat)
    end if
  end subroutine bind

  !> Does the model supply hessians_band? One call at q = v = 0 into band-sized arrays (its values
  !> are discarded; a failure there still means "supplied"). stat /= 0: out of memory.
  subroutine probe_band_hessians(self, lag, stat)
    class(vci_retraction_model_t), intent(inout) :: self
    class(vci_lagrangian_t), intent(inout) :: lag
    integer, intent(out) :: stat
    real(dp), allocatable :: z(:), bq(:, :), bv(:, :), bw2(:, :)
    integer :: s, bw
    bw = lag%hessian_bandwidth
    allocate (z(lag%n), bq(2 * bw + 1, lag%n), bv(2 * bw + 1, lag%n), bw2(2 * bw + 1, lag%n), stat=stat)
    if (stat /= 0) return
    z = 0.0_dp
    call lag%clear_not_provided(); s = 0
    call lag%hessians_band(z, z, bw, bq, bv, bw2, s)
    self%band_hessians = .not. lag%answered_not_provided()
    call lag%clear_not_provided()
  end subroutine probe_band_hessians

  !> Does the model supply hessians_sparse? One call at q = v = 0 into arrays of the declared length
  !> (values discarded; a failure there still means "supplied"). stat /= 0: out of memory.
  subroutine probe_sparse_hessians(self, lag, stat)
    class(vci_retraction_model_t), intent(inout) :: self
    class(vci_lagrangian_t), intent(inout) :: lag
    integer, intent(out) :: stat
    real(dp), allocatable :: z(:), a(:), b(:), c(:)
    integer :: s, nu
    nu = size(lag%hessian_pattern%upos)
    allocate (z(lag%n), a(nu), b(nu), c(nu), stat=stat)
    if (stat /= 0) return
    z = 0.0_dp
    call lag%clear_not_provided(); s = 0
    call lag%hessians_sparse(z, z, a, b, c, s)
    self%sparse_hessians = .not. lag%answered_not_provided()
    call lag%clear_not_provided()
  end subroutine probe_sparse_hessians

  !> The evaluation point and velocity of the segment (q, v, h).
  subroutine point_velocity(self, q, v, h)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    self%w = (v - q) / h
    if (self%rule == RETRACTION_LEFT) then
      self%pt = q
    else
      self%pt = 0.5_dp * (q + v)
    end if
  end subroutine point_velocity

  subroutine partials(self, q, v, h, stat)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    integer, intent(inout) :: stat
    call point_velocity(self, q, v, h)
    call self%lag%dl_dq(self%pt, self%w, self%lq, stat)
    if (stat /= 0) return
    call self%lag%dl_dv(self%pt, self%w, self%lv, stat)
  end subroutine partials

  !> D1 L_d: left h Lq - Lv; midpoint (h/2) Lq - Lv.
  subroutine d1(self, q, v, h, out, stat)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    call partials(self, q, v, h, stat)
    if (self%rule == RETRACTION_LEFT) then
      out = h * self%lq - self%lv
    else
      out = 0.5_dp * h * self%lq - self%lv
    end if
  end subroutine d1

  !> D2 L_d: left Lv; midpoint (h/2) Lq + Lv.
  subroutine d2(self, q, v, h, out, stat)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    call partials(self, q, v, h, stat)
    if (self%rule == RETRACTION_LEFT) then
      out = self%lv
    else
      out = 0.5_dp * h * self%lq + self%lv
    end if
  end subroutine d2

  !> D3 L_d = L - Lv . w (both rules).
  subroutine d3(self, q, v, h, out, stat)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out
    integer, intent(inout) :: stat
    real(dp) :: l
    call point_velocity(self, q, v, h)
    call self%lag%dl_dv(self%pt, self%w, self%lv, stat)
    if (stat /= 0) return
    call self%lag%lagrangian(self%pt, self%w, l, stat)
    out = l - dot_product(self%lv, self%w)
  end subroutine d3

  !> dD1/dv: left Lqv - Lvv/h; midpoint (h/4) Lqq + (Lqv - Lvq)/2 - Lvv/h (Lvq = Lqv^T).
  subroutine mixed_hessian(self, q, v, h, hess, stat)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: hess(:, :)
    integer, intent(inout) :: stat
    if (.not. self%work%has_hessians) then
      hess = 0.0_dp
      call self%not_provided(stat); return
    end if
    call point_velocity(self, q, v, h)
    if (self%hessian_bandwidth >= 0) hess = 0.0_dp   ! (mixed_block writes the band only)
    call mixed_block(self, h, hess, stat)
  end subroutine mixed_hessian

  !> D2 D1 L_d of the rule from L's Hessian blocks at the point and velocity already set (pt, w).
  subroutine mixed_block(self, h, hess, stat)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: h
    real(dp), intent(out) :: hess(:, :)
    integer, intent(inout) :: stat
    integer :: s
    if (self%band_hessians) then     ! (the band only, whatever the debug check: the rest is zero)
      call lagrangian_band_hessians(self%lag, self%work, self%pt, self%w, self%hessian_bandwidth, &
                                    self%lqq, self%lqv, self%lvv, s)
      if (s /= VCI_OK) then
        stat = failure_code(self, s); return
      end if
      if (self%check_bandwidth) hess = 0.0_dp   ! (Newton's matrix is then not zeroed on the band alone)
      call band_stored_mixed_block(self, h, hess)
      return
    end if
    if (self%sparse_hessians) then   ! (small systems, or the debug check: the dense matrix from the pattern)
      call lagrangian_sparse_hessians(self%lag, self%work, self%hessian_pattern, self%pt, self%w, self%sqq, &
                                      self%sqv, self%svv, s)
      if (s /= VCI_OK) then
        stat = failure_code(self, s); return
      end if
      hess = 0.0_dp
      call sparse_mixed_values(self, h, self%hessian_pattern, hess_dense=hess)
      return
    end if
    call lagrangian_hessians(self%lag, self%work, self%pt, self%w, self%lqq, self%lqv, self%lvv, s)
    if (s /= VCI_OK) then
      stat = failure_code(self, s); return
    end if
    if (self%hessian_bandwidth >= 0 .and. .not. self%check_bandwidth) then   ! (the debug check sees all entries)
      call banded_mixed_block(self, h, hess)
    else if (self%rule == RETRACTION_LEFT) then
      hess = self%lqv - self%lvv / h
    else
      hess = 0.25_dp * h * self%lqq + 0.5_dp * (self%lqv - transpose(self%lqv)) - self%lvv / h
    end if
  end subroutine mixed_block

  !> mixed_block's formulas on the declared band only (the blocks vanish outside it): O(n bw)
  !> arithmetic, no transpose temporary; the entries outside the band are not written (the caller
  !> zeroed them: Newton's matrix is zeroed on its band alone, vci_scheme's zero_jacobian).
  subroutine banded_mixed_block(self, h, hess)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: h
    real(dp), intent(inout) :: hess(:, :)
    integer :: i, j, n, bw
    n = size(hess, 1); bw = self%hessian_bandwidth
    do j = 1, n
      do i = max(1, j - bw), min(n, j + bw)
        if (self%rule == RETRACTION_LEFT) then
          hess(i, j) = self%lqv(i, j) - self%lvv(i, j) / h
        else
          hess(i, j) = 0.25_dp * h * self%lqq(i, j) + 0.5_dp * (self%lqv(i, j) - self%lqv(j, i)) - self%lvv(i, j) / h
        end if
      end do
    end do
  end subroutine banded_mixed_block

  !> banded_mixed_block from the blocks in band storage (hessians_band): entry (i, j) of a block
  !> at row k + i - j, k = bw + 1; L_vq(i, j) = L_qv(j, i) at row k + j - i of column i.
  subroutine band_stored_mixed_block(self, h, hess)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: h
    real(dp), intent(inout) :: hess(:, :)
    integer :: i, j, n, bw, k
    n = size(hess, 1); bw = self%hessian_bandwidth; k = bw + 1
    do j = 1, n
      do i = max(1, j - bw), min(n, j + bw)
        if (self%rule == RETRACTION_LEFT) then
          hess(i, j) = self%lqv(k + i - j, j) - self%lvv(k + i - j, j) / h
        else
          hess(i, j) = 0.25_dp * h * self%lqq(k + i - j, j) + 0.5_dp * (self%lqv(k + i - j, j) - &
                       self%lqv(k + j - i, i)) - self%lvv(k + i - j, j) / h
        end if
      end do
    end do
  end subroutine band_stored_mixed_block

  subroutine constraint_forms(self, q, omega, stat)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: omega(:, :)
    integer, intent(inout) :: stat
    call self%lag%constraint_forms(q, omega, stat)
  end subroutine constraint_forms

  !> omega_d(base, other, h) = Omega(point)^T (other - base)/h at the rule's point.
  subroutine discrete_constraint(self, base, other, h, out, stat)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: base(:), other(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    integer :: mu
    call point_velocity(self, base, other, h)
    call self%lag%constraint_forms(self%pt, self%om(:, 1:self%m), stat)
    do mu = 1, self%m
      out(mu) = dot_product(self%om(:, mu), self%w)
    end do
  end subroutine discrete_constraint

  !> The segment of the sub-step from the known point a with increment d (dir = +1: from a to a + d;
  !> -1: from a + d to a): its evaluation point and velocity, w = dir d / h exactly.
  subroutine segment_inc(self, a, d, h, dir)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: a(:), d(:), h
    integer, intent(in) :: dir
    self%w = (real(dir, dp) / h) * d
    if (self%rule == RETRACTION_MIDPOINT) then
      self%pt = a + 0.5_dp * d
    else if (dir > 0) then
      self%pt = a
    else
      self%pt = a + d
    end if
  end subroutine segment_inc

  !> The segment's point and velocity (segment_inc) and the partials lq = dL/dq, lv = dL/dqdot there
  !> (stat: the first failing callback's).
  subroutine segment_partials(self, a, d, h, dir, stat)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: a(:), d(:), h
    integer, intent(in) :: dir
    integer, intent(inout) :: stat
    call segment_inc(self, a, d, h, dir)
    call self%lag%dl_dq(self%pt, self%w, self%lq, stat)
    if (stat /= 0) return
    call self%lag%dl_dv(self%pt, self%w, self%lv, stat)
  end subroutine segment_partials

  !> s D1 L^s of the sub-step (forward D1 L_d(a, b), backward -D2 L_d(b, a)) from the increment.
  subroutine d1s_inc(self, a, d, h, dir, out, stat)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: a(:), d(:), h
    integer, intent(in) :: dir
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    real(dp) :: c
    call segment_partials(self, a, d, h, dir, stat)
    if (stat /= 0) return
    c = h
    if (self%rule == RETRACTION_MIDPOINT) c = 0.5_dp * h
    if (dir > 0) then
      out = c * self%lq - self%lv                     ! D1 L_d(a, b)
    else if (self%rule == RETRACTION_MIDPOINT) then
      out = -(c * self%lq + self%lv)                  ! -D2 L_d(b, a), midpoint
    else
      out = -self%lv                                  ! -D2 L_d(b, a), left
    end if
  end subroutine d1s_inc

  !> The momentum at the unknown end (forward D2 L_d(a, b), backward -D1 L_d(b, a)).
  subroutine pout_inc(self, a, d, h, dir, out, stat)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: a(:), d(:), h
    integer, intent(in) :: dir
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    call segment_partials(self, a, d, h, dir, stat)
    if (stat /= 0) return
    if (self%rule == RETRACTION_MIDPOINT) then
      out = real(dir, dp) * 0.5_dp * h * self%lq + self%lv   ! D2 L_d(a, b) or -D1 L_d(b, a), midpoint
    else if (dir > 0) then
      out = self%lv                                          ! D2 L_d(a, b), left
    else
      out = self%lv - h * self%lq                            ! -D1 L_d(b, a), left
    end if
  end subroutine pout_inc

  !> The force impulse of the sub-step, dir h dL/dq at the segment's point and velocity: the momentum
  !> at the unknown end is p_a - Omega(a) lambda + this (forward (D1 + D2) L_d(a, b); backward minus
  !> that of L_d(b, a)), a sum with no cancellation between kinetic terms.
  subroutine impulse_inc(self, a, d, h, dir, out, stat)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: a(:), d(:), h
    integer, intent(in) :: dir
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    call segment_inc(self, a, d, h, dir)
    call self%lag%dl_dq(self%pt, self%w, self%lq, stat)
    out = (real(dir, dp) * h) * self%lq
  end subroutine impulse_inc

  !> E_d = -D3 L_d = Lv . w - L at the segment (both directions).
  subroutine energy_inc(self, a, d, h, dir, e, stat)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: a(:), d(:), h
    integer, intent(in) :: dir
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    real(dp) :: l
    call segment_inc(self, a, d, h, dir)
    call self%lag%dl_dv(self%pt, self%w, self%lv, stat)
    if (stat /= 0) return
    call self%lag%lagrangian(self%pt, self%w, l, stat)
    e = dot_product(self%lv, self%w) - l
  end subroutine energy_inc

  !> d(s D1 L^s)/db of the sub-step: forward the mixed Hessian of L_d(a, b), backward minus the
  !> transpose of that of L_d(b, a) (the formulas of mixed_hessian at the segment's point and velocity).
  subroutine jacobian_inc(self, a, d, h, dir, jac, stat)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: a(:), d(:), h
    integer, intent(in) :: dir
    real(dp), intent(inout) :: jac(:, :)
    integer, intent(inout) :: stat
    integer :: s, i, j, bw
    real(dp) :: t
    if (.not. self%work%has_hessians) then
      jac = 0.0_dp
      call self%not_provided(stat); return
    end if
    call segment_inc(self, a, d, h, dir)
    s = VCI_OK
    call mixed_block(self, h, jac, s)
    if (s /= VCI_OK) then
      stat = s; return
    end if
    if (dir >= 0) return
    ! jac = -transpose(jac) in place: the array expression would put a temporary on the heap
    ! (on the band alone when one is declared: the rest is zero)
    bw = size(jac, 1)
    if (self%hessian_bandwidth >= 0 .and. .not. self%check_bandwidth) bw = self%hessian_bandwidth
    do j = 1, size(jac, 2)
      jac(j, j) = -jac(j, j)
      do i = j + 1, min(size(jac, 1), j + bw)
        t = jac(i, j); jac(i, j) = -jac(j, i); jac(j, i) = -t
      end do
    end do
  end subroutine jacobian_inc

  !> jacobian_inc on the declared band, into compact band storage ab(2 bw + 1, n) (entry (i, j) at
  !> row bw + 1 + i - j, LAPACK's layout without fill-in rows): from the model's banded Hessians
  !> when it gives them, else from its dense ones read on the band. O(n bw); stat as jacobian_inc's.
  subroutine jacobian_inc_band(self, a, d, h, dir, ab, stat)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: a(:), d(:), h
    integer, intent(in) :: dir
    real(dp), intent(inout) :: ab(:, :)
    integer, intent(inout) :: stat
    integer :: s, i, j, n, bw, k
    real(dp) :: t
    bw = self%hessian_bandwidth; n = size(ab, 2); k = bw + 1
    if (.not. self%work%has_hessians) then
      ab = 0.0_dp
      call self%not_provided(stat); return
    end if
    call segment_inc(self, a, d, h, dir)
    s = VCI_OK
    if (self%band_hessians) then
      call lagrangian_band_hessians(self%lag, self%work, self%pt, self%w, bw, self%lqq, self%lqv, self%lvv, s)
    else
      call lagrangian_hessians(self%lag, self%work, self%pt, self%w, self%lqq, self%lqv, self%lvv, s)
    end if
    if (s /= VCI_OK) then
      stat = failure_code(self, s); return
    end if
    if (self%band_hessians) then    ! (one loop per case: a branch per entry cost ~25 % more instructions)
      if (self%rule == RETRACTION_LEFT) then
        do j = 1, n
          do i = max(1, j - bw), min(n, j + bw)
            ab(k + i - j, j) = self%lqv(k + i - j, j) - self%lvv(k + i - j, j) / h
          end do
        end do
      else
        do j = 1, n
          do i = max(1, j - bw), min(n, j + bw)
            ab(k + i - j, j) = 0.25_dp * h * self%lqq(k + i - j, j) + 0.5_dp * (self%lqv(k + i - j, j) - &
                               self%lqv(k + j - i, i)) - self%lvv(k + i - j, j) / h
          end do
        end do
      end if
    else
      do j = 1, n
        do i = max(1, j - bw), min(n, j + bw)
          ab(k + i - j, j) = mixed_entry(self, h, i, j)
        end do
      end do
    end if
    if (dir >= 0) return
    ! -transpose in place on the band: (i, j) and (j, i) sit at rows k + i - j and k + j - i
    do j = 1, n
      ab(k, j) = -ab(k, j)
      do i = j + 1, min(n, j + bw)
        t = ab(k + i - j, j); ab(k + i - j, j) = -ab(k + j - i, i); ab(k + j - i, i) = -t
      end do
    end do
  end subroutine jacobian_inc_band

  !> jacobian_inc into the values val(k) of a declared sparse pattern pat (entry (pat%rowind(k), j)):
  !> from the model's sparse Hessians when it gives them (O(nnz)), else from its dense ones (or their
  !> differences) read in the pattern. stat as jacobian_inc's.
  subroutine jacobian_inc_sparse(self, a, d, h, dir, pat, val, stat)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: a(:), d(:), h
    integer, intent(in) :: dir
    type(vci_sparse_pattern_t), intent(in) :: pat
    real(dp), intent(inout) :: val(:)
    integer, intent(inout) :: stat
    integer :: s, i, j, k
    real(dp) :: t
    if (.not. self%work%has_hessians) then
      val = 0.0_dp
      call self%not_provided(stat); return
    end if
    call segment_inc(self, a, d, h, dir)
    s = VCI_OK
    if (self%sparse_hessians) then
      call lagrangian_sparse_hessians(self%lag, self%work, pat, self%pt, self%w, self%sqq, self%sqv, self%svv, s)
    else
      call lagrangian_hessians(self%lag, self%work, self%pt, self%w, self%lqq, self%lqv, self%lvv, s)
    end if
    if (s /= VCI_OK) then
      stat = failure_code(self, s); return
    end if
    if (self%sparse_hessians) then
      call sparse_mixed_values(self, h, pat, val=val)
    else
      do j = 1, pat%n
        do k = pat%colptr(j), pat%colptr(j + 1) - 1
          i = pat%rowind(k)
          val(k) = mixed_entry(self, h, i, j)
        end do
      end do
    end if
    if (dir >= 0) return
    ! -transpose in place in the (symmetric) pattern: entry k's transpose sits at tpos(k)
    do k = 1, size(val)
      if (pat%tpos(k) < k) cycle
      t = val(k); val(k) = -val(pat%tpos(k)); val(pat%tpos(k)) = -t
    end do
  end subroutine jacobian_inc_sparse

  !> mixed_block's formulas from the blocks in the pattern's order (sqq, sqv, svv; L_vq(i, j) =
  !> L_qv(j, i) at tpos): into val (pattern order) or the dense hess_dense (entries outside the
  !> pattern untouched). O(nnz).
  subroutine sparse_mixed_values(self, h, pat, val, hess_dense)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: h
    type(vci_sparse_pattern_t), intent(in) :: pat
    real(dp), intent(inout), optional :: val(:), hess_dense(:, :)
    integer :: i, j, k
    real(dp) :: v
    do j = 1, pat%n
      do k = pat%colptr(j), pat%colptr(j + 1) - 1
        i = pat%rowind(k)
        if (self%rule == RETRACTION_LEFT) then
          v = self%sqv(k) - self%svv(k) / h
        else
          v = 0.25_dp * h * self%sqq(k) + 0.5_dp * (self%sqv(k) - self%sqv(pat%tpos(k))) - self%svv(k) / h
        end if
        if (present(val)) val(k) = v
        if (present(hess_dense)) hess_dense(i, j) = v
      end do
    end do
  end subroutine sparse_mixed_values

  !> Entry (i, j), |i - j| <= bw, of mixed_block's D2 D1 L_d from the blocks as they are stored
  !> (band storage with hessians_band, else dense).
  pure real(dp) function mixed_entry(self, h, i, j) result(v)
    class(vci_retraction_model_t), intent(in) :: self
    real(dp), intent(in) :: h
    integer, intent(in) :: i, j
    real(dp) :: qq, qv, vq, vv
    integer :: k
    if (self%band_hessians) then
      k = self%hessian_bandwidth + 1
      qq = self%lqq(k + i - j, j); qv = self%lqv(k + i - j, j); vq = self%lqv(k + j - i, i); vv = self%lvv(k + i - j, j)
    else
      qq = self%lqq(i, j); qv = self%lqv(i, j); vq = self%lqv(j, i); vv = self%lvv(i, j)
    end if
    if (self%rule == RETRACTION_LEFT) then
      v = qv - vv / h
    else
      v = 0.25_dp * h * qq + 0.5_dp * (qv - vq) - vv / h
    end if
  end function mixed_entry

  !> omega_d(a, b, h) = Omega(point)^T d / h with the rule's point of the segment based at a.
  subroutine constraint_inc(self, a, d, h, out, stat)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: a(:), d(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    integer :: mu
    if (self%rule == RETRACTION_LEFT) then
      call self%lag%constraint_forms(a, self%om(:, 1:self%m), stat)
    else
      self%pt = a + 0.5_dp * d
      call self%lag%constraint_forms(self%pt, self%om(:, 1:self%m), stat)
    end if
    do mu = 1, self%m
      out(mu) = dot_product(self%om(:, mu), d) / h
    end do
  end subroutine constraint_inc

  subroutine gaps(self, q, g, stat)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    call self%lag%gaps(q, g, stat)
  end subroutine gaps

  subroutine gap_gradients(self, q, dg, stat)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    call self%lag%gap_gradients(q, dg, stat)
  end subroutine gap_gradients

  subroutine gap_gradient(self, q, j, dg, stat)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    integer, intent(in) :: j
    real(dp), intent(out) :: dg(:)
    integer, intent(inout) :: stat
    call self%lag%gap_gradient(q, j, dg, stat)
  end subroutine gap_gradient

  !> H(q, p): the model's, else E(q, w) with dL/dqdot(q, w) = p.
  subroutine energy(self, q, p, e, stat)
    class(vci_retraction_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    integer :: s
    if (self%has_model_energy) then
      call self%lag%energy(q, p, e, stat)
      return
    end if
    self%w = 0.0_dp
    call lagrangian_hamiltonian(self%lag, self%work, q, p, self%w, e, s)
    if (s /= VCI_OK) stat = failure_code(self, s)
  end subroutine energy

  !> The stat to report for a failed derived quantity: the callback's own code when one failed
  !> (so an unrecoverable code stays unrecoverable), else 1 (NaN/Inf or a Legendre inversion that
  !> did not converge: recoverable at a trial point).
  integer function failure_code(self, status)
    class(vci_retraction_model_t), intent(in) :: self
    integer, intent(in) :: status
    failure_code = 1
    if (status == VCI_ERR_CALLBACK .and. self%work%code /= 0) failure_code = self%work%code
  end function failure_code
end module vci_retraction
