!> The continuous model a user extends: a Lagrangian L(q, qdot) and, only when the scene needs them,
!> its Hessian blocks, constraint one-forms Omega(q), walls and a Hamiltonian H(q, p) (sizes, forms,
!> walls and H come from `vci_model_base_t`). The library builds a discrete Lagrangian from it by the
!> scheme chosen at run time (`left`, `midpoint`, `lobatto` with s stages; docs/SCHEMES.md), derives
!> the energy E(q, qdot) = dL/dqdot . qdot - L itself, builds the discrete constraint from Omega, and
!> differences the Hessian blocks when they are absent.
!>
!> Required: lagrangian (the value of L), dl_dq, dl_dv. A C or legacy adapter that lacks one of them
!> answers "not provided" (`not_provided`); the integrator then refuses the model with VCI_ERR_ARGUMENT.
!> Callbacks receive `stat` preset to 0 and follow the callback contract of vci_model: 0 success,
!> > 0 a recoverable failure, < 0 an unrecoverable one.
module vci_lagrangian
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use vci_kinds, only: dp
  use vci_status, only: VCI_OK, VCI_ERR_CALLBACK, VCI_ERR_NONFINITE, VCI_ERR_NEWTON
  use vci_model_base, only: vci_model_base_t
  use vci_lapack, only: dgetrf, dgetrs
  implicit none
  private

  !> A model given by its continuous Lagrangian L(q, qdot): extend it and write lagrangian, dl_dq,
  !> dl_dv; the integrator discretises it by the scheme set_scheme chooses.
  type, abstract, extends(vci_model_base_t), public :: vci_lagrangian_t
  contains
    !> L(q, v)
    procedure(l_value), deferred :: lagrangian
    !> dL/dq(q, v) in R^n
    procedure(l_partial), deferred :: dl_dq
    !> dL/dqdot(q, v) in R^n (the momentum)
    procedure(l_partial), deferred :: dl_dv
    !> lqq(i, j) = d2L/dq_i dq_j, lqv(i, j) = d2L/dq_i dv_j, lvv(i, j) = d2L/dv_i dv_j (each n x n).
    procedure :: hessians => not_provided_hessians
  end type vci_lagrangian_t

  abstract interface
    !> l = L(q, v).
    subroutine l_value(self, q, v, l, stat)
      import :: vci_lagrangian_t, dp
      class(vci_lagrangian_t), intent(inout) :: self
      real(dp), intent(in) :: q(:), v(:)
      real(dp), intent(out) :: l
      integer, intent(inout) :: stat
    end subroutine l_value
    !> out = a partial of L at (q, v) in R^n (dL/dq or dL/dqdot).
    subroutine l_partial(self, q, v, out, stat)
      import :: vci_lagrangian_t, dp
      class(vci_lagrangian_t), intent(inout) :: self
      real(dp), intent(in) :: q(:), v(:)
      real(dp), intent(out) :: out(:)
      integer, intent(inout) :: stat
    end subroutine l_partial
  end interface

  !> Workspace for differenced Hessians and the Legendre inversion (sized once, never per step).
  type, public :: vci_lagrangian_work_t
    logical :: has_hessians = .false.
    integer :: code = 0   !< stat of the last callback that failed here (its sign: recoverable or not)
    real(dp), allocatable :: qp(:), vp(:), fp(:), fm(:), w(:), dw(:), lv(:), lvv(:, :), lqq(:, :), lqv(:, :)
    integer, allocatable :: ipiv(:)
  end type vci_lagrangian_work_t

  public :: lagrangian_work_setup, lagrangian_hessians, lagrangian_energy, lagrangian_hamiltonian

  real(dp), parameter :: fd_rel = 6.0e-6_dp   ! ~ eps**(1/3): central differences

contains

  !> lqq(i, j) = d2L/dq_i dq_j, lqv(i, j) = d2L/dq_i dv_j, lvv(i, j) = d2L/dv_i dv_j (each n x n).
  subroutine not_provided_hessians(self, q, v, lqq, lqv, lvv, stat)
    class(vci_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: lqq(:, :), lqv(:, :), lvv(:, :)
    integer, intent(inout) :: stat
    lqq = 0.0_dp; lqv = 0.0_dp; lvv = 0.0_dp
    call self%not_provided(stat)
  end subroutine not_provided_hessians

  !> Size the workspace for n coordinates; stat /= 0: out of memory.
  subroutine lagrangian_work_setup(work, n, stat)
    type(vci_lagrangian_work_t), intent(inout) :: work
    integer, intent(in) :: n
    integer, intent(out) :: stat
    ! array by array: after an allocate that failed part-way some are allocated and some not
    if (allocated(work%qp)) deallocate (work%qp)
    if (allocated(work%vp)) deallocate (work%vp)
    if (allocated(work%fp)) deallocate (work%fp)
    if (allocated(work%fm)) deallocate (work%fm)
    if (allocated(work%w)) deallocate (work%w)
    if (allocated(work%dw)) deallocate (work%dw)
    if (allocated(work%lv)) deallocate (work%lv)
    if (allocated(work%lvv)) deallocate (work%lvv)
    if (allocated(work%lqq)) deallocate (work%lqq)
    if (allocated(work%lqv)) deallocate (work%lqv)
    if (allocated(work%ipiv)) deallocate (work%ipiv)
    allocate (work%qp(n), work%vp(n), work%fp(n), work%fm(n), work%w(n), work%dw(n), work%lv(n), &
              work%lvv(n, n), work%lqq(n, n), work%lqv(n, n), work%ipiv(n), stat=stat)
  end subroutine lagrangian_work_setup

  !> The three Hessian blocks at (q, v): the model's own when it has them (work%has_hessians), else
  !> central differences of dl_dq and dl_dv. stat: VCI_OK, VCI_ERR_CALLBACK (the callback's own code
  !> in work%code) or VCI_ERR_NONFINITE.
  subroutine lagrangian_hessians(lag, work, q, v, lqq, lqv, lvv, stat)
    class(vci_lagrangian_t), intent(inout) :: lag
    type(vci_lagrangian_work_t), intent(inout) :: work
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: lqq(:, :), lqv(:, :), lvv(:, :)
    integer, intent(out) :: stat
    integer :: i, n, s
    real(dp) :: d
    n = size(q)
    stat = VCI_OK
    if (work%has_hessians) then
      s = 0
      call lag%hessians(q, v, lqq, lqv, lvv, s)
      if (s /= 0) then
        work%code = s
        stat = VCI_ERR_CALLBACK; return
      end if
      if (lag%hessian_bandwidth >= 0 .and. .not. lag%check_bandwidth) then
        ! declared band: only its entries are read (vci_retraction's banded_mixed_block)
        if (.not. (finite_band(lqq, lag%hessian_bandwidth) .and. finite_band(lqv, lag%hessian_bandwidth) .and. &
                   finite_band(lvv, lag%hessian_bandwidth))) stat = VCI_ERR_NONFINITE
      else if (.not. (finite_matrix(lqq) .and. finite_matrix(lqv) .and. finite_matrix(lvv))) then
        stat = VCI_ERR_NONFINITE
      end if
      return
    end if
    work%qp(1:n) = q; work%vp(1:n) = v
    do i = 1, n
      ! columns in q: d(dL/dq)/dq_i
      d = fd_rel * max(abs(q(i)), 1.0_dp)
      work%qp(i) = q(i) + d
      call partial(lag, work, .true., work%qp(1:n), v, work%fp(1:n), stat); if (stat /= VCI_OK) return
      work%qp(i) = q(i) - d
      call partial(lag, work, .true., work%qp(1:n), v, work%fm(1:n), stat); if (stat /= VCI_OK) return
      work%qp(i) = q(i)
      lqq(:, i) = (work%fp(1:n) - work%fm(1:n)) / (2.0_dp * d)
      ! columns in v: d(dL/dq)/dv_i and d(dL/dv)/dv_i
      d = fd_rel * max(abs(v(i)), 1.0_dp)
      work%vp(i) = v(i) + d
      call partial(lag, work, .true., q, work%vp(1:n), work%fp(1:n), stat); if (stat /= VCI_OK) return
      work%vp(i) = v(i) - d
      call partial(lag, work, .true., q, work%vp(1:n), work%fm(1:n), stat); if (stat /= VCI_OK) return
      lqv(:, i) = (work%fp(1:n) - work%fm(1:n)) / (2.0_dp * d)
      work%vp(i) = v(i) + d
      call partial(lag, work, .false., q, work%vp(1:n), work%fp(1:n), stat); if (stat /= VCI_OK) return
      work%vp(i) = v(i) - d
      call partial(lag, work, .false., q, work%vp(1:n), work%fm(1:n), stat); if (stat /= VCI_OK) return
      work%vp(i) = v(i)
      lvv(:, i) = (work%fp(1:n) - work%fm(1:n)) / (2.0_dp * d)
    end do
  end subroutine lagrangian_hessians

  !> No NaN or Inf in a: one test on the sum (3 n^2 calls of ieee_is_finite cost 38 % of a chain's
  !> impact steps at n = 128, docs/bench/chain.md), each entry only when the sum is not finite.
  pure logical function finite_matrix(a) result(ok)
    real(dp), intent(in) :: a(:, :)
    ok = abs(sum(a)) <= huge(1.0_dp)
    if (.not. ok) ok = all(ieee_is_finite(a))     ! (finite entries whose sum overflows)
  end function finite_matrix

  !> No NaN or Inf in the band |i - j| <= bw of the square matrix a.
  pure logical function finite_band(a, bw) result(ok)
    real(dp), intent(in) :: a(:, :)
    integer, intent(in) :: bw
    integer :: i, j, n
    real(dp) :: acc
    n = size(a, 1)
    acc = 0.0_dp
    do j = 1, n
      do i = max(1, j - bw), min(n, j + bw)
        acc = acc + a(i, j)
      end do
    end do
    ok = abs(acc) <= huge(1.0_dp)
    if (ok) return
    do j = 1, n                              ! (finite entries whose sum overflows)
      do i = max(1, j - bw), min(n, j + bw)
        if (.not. ieee_is_finite(a(i, j))) return
      end do
    end do
    ok = .true.
  end function finite_band

  !> dL/dq (wrt_q) or dL/dqdot at (q, v), with the callback's status checked.
  subroutine partial(lag, work, wrt_q, q, v, out, stat)
    class(vci_lagrangian_t), intent(inout) :: lag
    type(vci_lagrangian_work_t), intent(inout) :: work
    logical, intent(in) :: wrt_q
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(out) :: stat
    integer :: s
    s = 0
    if (wrt_q) then
      call lag%dl_dq(q, v, out, s)
    else
      call lag%dl_dv(q, v, out, s)
    end if
    stat = VCI_OK
    if (s /= 0) then
      work%code = s
      stat = VCI_ERR_CALLBACK
    else if (.not. all(ieee_is_finite(out))) then
      stat = VCI_ERR_NONFINITE
    end if
  end subroutine partial

  !> The energy E(q, v) = dL/dv . v - L of the continuous model at a velocity.
  subroutine lagrangian_energy(lag, work, q, v, e, stat)
    class(vci_lagrangian_t), intent(inout) :: lag
    type(vci_lagrangian_work_t), intent(inout) :: work
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: e
    integer, intent(out) :: stat
    integer :: s, n
    real(dp) :: l
    n = size(q)
    call partial(lag, work, .false., q, v, work%lv(1:n), stat)
    if (stat /= VCI_OK) return
    s = 0
    call lag%lagrangian(q, v, l, s)
    if (s /= 0) then
      work%code = s
      stat = VCI_ERR_CALLBACK; return
    end if
    e = dot_product(work%lv(1:n), v) - l
    if (.not. ieee_is_finite(e)) stat = VCI_ERR_NONFINITE
  end subroutine lagrangian_energy

  !> H(q, p) = E(q, w) with dL/dv(q, w) = p (Legendre inversion by Newton on w from w = v_guess,
  !> with the velocity Hessian; one iteration when L is quadratic in the velocity). Used for the
  !> hamiltonian impact condition when the model does not supply H. VCI_ERR_NEWTON when the
  !> inversion does not converge (a degenerate L at q).
  subroutine lagrangian_hamiltonian(lag, work, q, p, v_guess, e, stat)
    class(vci_lagrangian_t), intent(inout) :: lag
    type(vci_lagrangian_work_t), intent(inout) :: work
    real(dp), intent(in) :: q(:), p(:), v_guess(:)
    real(dp), intent(out) :: e
    integer, intent(out) :: stat
    integer :: it, n, info
    real(dp) :: size_p
    n = size(q)
    e = 0.0_dp
    work%w(1:n) = v_guess
    size_p = maxval(abs(p))
    do it = 1, 30
      call partial(lag, work, .false., q, work%w(1:n), work%lv(1:n), stat)
      if (stat /= VCI_OK) return
      work%dw(1:n) = work%lv(1:n) - p
      if (it > 1 .and. maxval(abs(work%dw(1:n))) <= 4.0_dp * epsilon(1.0_dp) * max(size_p, &
          maxval(abs(work%lv(1:n))), tiny(1.0_dp))) exit
      call lagrangian_hessians(lag, work, q, work%w(1:n), work%lqq, work%lqv, work%lvv, stat)
      if (stat /= VCI_OK) return
      ! differenced blocks of huge but finite values can overflow: nothing non-finite goes to LAPACK
      if (.not. (all(ieee_is_finite(work%lvv)) .and. all(ieee_is_finite(work%dw(1:n))))) then
        stat = VCI_ERR_NONFINITE; return
      end if
      call dgetrf(n, n, work%lvv, n, work%ipiv, info)
      if (info /= 0) then
        stat = VCI_ERR_NEWTON; return
      end if
      call dgetrs('N', n, 1, work%lvv, n, work%ipiv, work%dw, n, info)
      work%w(1:n) = work%w(1:n) - work%dw(1:n)
      if (.not. all(ieee_is_finite(work%w(1:n)))) then
        stat = VCI_ERR_NONFINITE; return
      end if
      if (it == 30) then
        stat = VCI_ERR_NEWTON; return
      end if
    end do
    call lagrangian_energy(lag, work, q, work%w(1:n), e, stat)
  end subroutine lagrangian_hamiltonian
end module vci_lagrangian
