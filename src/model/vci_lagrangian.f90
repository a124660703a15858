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
  use vci_status, only: VCI_OK, VCI_ERR_CALLBACK, VCI_ERR_NONFINITE, VCI_ERR_NEWTON, VCI_ERR_ARGUMENT, VCI_ERR_MEMORY
  use vci_model_base, only: vci_model_base_t
  use vci_lapack, only: dgetrf, dgetrs
  use vci_banded, only: band_lu, band_solve
  use vci_sparse, only: vci_sparse_lu_t, vci_sparse_pattern_t
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
    !> The same blocks on a declared band |i - j| <= bw only, in LAPACK band storage (each
    !> (2 bw + 1) x n): lqq(bw + 1 + i - j, j) = d2L/dq_i dq_j, and so lqv, lvv. Optional; with a
    !> declared bandwidth the `left` and `midpoint` schemes then keep no n x n Hessian block.
    procedure :: hessians_band => not_provided_hessians_band
    !> The same blocks in a declared sparse pattern (declare_pattern): lqq(k) = d2L/dq_i dq_j for
    !> the k-th declared entry (i = rowind(k) in column j, the declared arrays' order; repeated
    !> entries are summed), and so lqv, lvv; each of the declared length colptr(n + 1) - 1.
    !> Optional; with a declared pattern the `left` and `midpoint` schemes then keep no n x n
    !> Hessian block and assemble Newton's matrix in the pattern (O(nnz)).
    procedure :: hessians_sparse => not_provided_hessians_sparse
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
    !> the model's hessians_band is used (with hessian_bandwidth >= 0): lqq, lqv hold its band
    !> storage, (2 bw + 1) x n, and lvv the velocity block's with bw rows for the LU's fill-in above
    !> it, (3 bw + 1) x n (the Legendre inversion factorises it in place)
    logical :: has_band_hessians = .false.
    integer :: code = 0   !< stat of the last callback that failed here (its sign: recoverable or not)
    real(dp), allocatable :: qp(:), vp(:), fp(:), fm(:), w(:), dw(:), lv(:), lvv(:, :), lqq(:, :), lqv(:, :)
    real(dp), allocatable :: bvv(:, :)   !< hessians_band's velocity block, (2 bw + 1) x n (else 1 x 1)
    integer, allocatable :: ipiv(:)
    !> the model's hessians_sparse is used (a declared pattern): the dense blocks above are 1 x 1,
    !> uqq, uqv, uvv take the callback's values (declared order), sqq, sqv, svv the pattern's
    !> (vci_sparse_pattern_t order), and the Legendre inversion factorises svv by KLU (slu)
    logical :: has_sparse_hessians = .false.
    real(dp), allocatable :: uqq(:), uqv(:), uvv(:), sqq(:), sqv(:), svv(:), ones(:), none(:, :)
    type(vci_sparse_lu_t) :: slu
  end type vci_lagrangian_work_t

  public :: lagrangian_work_setup, lagrangian_hessians, lagrangian_energy, lagrangian_hamiltonian
  public :: lagrangian_band_hessians, lagrangian_check_band
  public :: lagrangian_sparse_hessians, lagrangian_sparse_setup, check_point

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

  !> The banded blocks (band storage, (2 bw + 1) x n each) on |i - j| <= bw.
  subroutine not_provided_hessians_band(self, q, v, bw, lqq, lqv, lvv, stat)
    class(vci_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    integer, intent(in) :: bw
    real(dp), intent(out) :: lqq(:, :), lqv(:, :), lvv(:, :)
    integer, intent(inout) :: stat
    lqq = 0.0_dp; lqv = 0.0_dp; lvv = 0.0_dp
    if (bw < 0) return
    call self%not_provided(stat)
  end subroutine not_provided_hessians_band

  !> The sparse blocks (declared order, each of the declared pattern's length).
  subroutine not_provided_hessians_sparse(self, q, v, lqq, lqv, lvv, stat)
    class(vci_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: lqq(:), lqv(:), lvv(:)
    integer, intent(inout) :: stat
    lqq = 0.0_dp; lqv = 0.0_dp; lvv = 0.0_dp
    call self%not_provided(stat)
  end subroutine not_provided_hessians_sparse

  !> Size the workspace for the model's sparse Hessians (hessians_sparse, with the declared pattern
  !> pat of nnz_user declared entries): the dense blocks shrink to 1 x 1 (after
  !> lagrangian_work_setup), O(nnz) arrays instead. stat /= 0: out of memory.
  subroutine lagrangian_sparse_setup(work, pat, stat)
    type(vci_lagrangian_work_t), intent(inout) :: work
    type(vci_sparse_pattern_t), intent(in) :: pat
    integer, intent(out) :: stat
    integer :: nnz, nu
    nnz = pat%colptr(pat%n + 1) - 1; nu = size(pat%upos)
    if (allocated(work%lvv)) deallocate (work%lvv)
    if (allocated(work%lqq)) deallocate (work%lqq)
    if (allocated(work%lqv)) deallocate (work%lqv)
    if (allocated(work%uqq)) deallocate (work%uqq)
    if (allocated(work%uqv)) deallocate (work%uqv)
    if (allocated(work%uvv)) deallocate (work%uvv)
    if (allocated(work%sqq)) deallocate (work%sqq)
    if (allocated(work%sqv)) deallocate (work%sqv)
    if (allocated(work%svv)) deallocate (work%svv)
    if (allocated(work%ones)) deallocate (work%ones)
    if (allocated(work%none)) deallocate (work%none)
    allocate (work%lvv(1, 1), work%lqq(1, 1), work%lqv(1, 1), work%uqq(nu), work%uqv(nu), work%uvv(nu), &
              work%sqq(nnz), work%sqv(nnz), work%svv(nnz), work%ones(pat%n), work%none(1, 1), stat=stat)
    if (stat /= 0) return
    work%ones = 1.0_dp
    work%has_sparse_hessians = .true.
  end subroutine lagrangian_sparse_setup

  !> The model's sparse Hessian blocks at (q, v) in the pattern's order (lqq(k): entry
  !> (pat%rowind(k), j)), gathered from the callback's declared order (repeats summed; entries of
  !> the pattern the declaration lacks — transposes, the diagonal — are zero). O(nnz). stat:
  !> VCI_OK, VCI_ERR_CALLBACK (code in work%code) or VCI_ERR_NONFINITE.
  subroutine lagrangian_sparse_hessians(lag, work, pat, q, v, lqq, lqv, lvv, stat)
    class(vci_lagrangian_t), intent(inout) :: lag
    type(vci_lagrangian_work_t), intent(inout) :: work
    type(vci_sparse_pattern_t), intent(in) :: pat
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: lqq(:), lqv(:), lvv(:)
    integer, intent(out) :: stat
    integer :: s, k, p
    stat = VCI_OK
    s = 0
    call lag%hessians_sparse(q, v, work%uqq, work%uqv, work%uvv, s)
    if (s /= 0) then
      work%code = s
      stat = VCI_ERR_CALLBACK; return
    end if
    if (.not. (abs(sum(work%uqq) + sum(work%uqv) + sum(work%uvv)) <= huge(1.0_dp))) then
      if (.not. (all(ieee_is_finite(work%uqq)) .and. all(ieee_is_finite(work%uqv)) .and. &
                 all(ieee_is_finite(work%uvv)))) then
        stat = VCI_ERR_NONFINITE; return
      end if
    end if
    lqq = 0.0_dp; lqv = 0.0_dp; lvv = 0.0_dp
    do k = 1, size(pat%upos)
      p = pat%upos(k)
      lqq(p) = lqq(p) + work%uqq(k); lqv(p) = lqv(p) + work%uqv(k); lvv(p) = lvv(p) + work%uvv(k)
    end do
  end subroutine lagrangian_sparse_hessians

  !> Size the workspace for n coordinates; band (optional, >= 0): the Hessian blocks come from
  !> hessians_band with that half-bandwidth, so they are (2 bw + 1) x n (lvv: 3 bw + 1 rows), not
  !> n x n (work%has_band_hessians); pattern (optional): they come from hessians_sparse in that
  !> declared pattern, so the dense blocks are 1 x 1 and O(nnz) arrays hold them (lagrangian_sparse_setup).
  !> stat /= 0: out of memory.
  subroutine lagrangian_work_setup(work, n, stat, band, pattern)
    type(vci_lagrangian_work_t), intent(inout) :: work
    integer, intent(in) :: n
    integer, intent(out) :: stat
    integer, intent(in), optional :: band
    !> the model's hessians_sparse is used with this declared pattern: no dense blocks at all
    type(vci_sparse_pattern_t), intent(in), optional :: pattern
    integer :: rows, rows_vv
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
    if (allocated(work%bvv)) deallocate (work%bvv)
    rows = n; rows_vv = n
    work%has_band_hessians = .false.; work%has_sparse_hessians = .false.
    if (present(band)) then
      if (band >= 0) then
        rows = 2 * band + 1; rows_vv = 3 * band + 1
        work%has_band_hessians = .true.
      end if
    end if
    if (present(pattern)) then
      rows = 1; rows_vv = 1
    end if
    allocate (work%qp(n), work%vp(n), work%fp(n), work%fm(n), work%w(n), work%dw(n), work%lv(n), &
              work%lvv(rows_vv, n), work%lqq(rows, n), work%lqv(rows, n), work%ipiv(n), stat=stat)
    if (stat == 0) then
      if (work%has_band_hessians) then
        allocate (work%bvv(rows, n), stat=stat)
      else
        allocate (work%bvv(1, 1), stat=stat)
      end if
    end if
    if (stat == 0 .and. present(pattern)) call lagrangian_sparse_setup(work, pattern, stat)
  end subroutine lagrangian_work_setup

  !> The model's banded Hessian blocks at (q, v) in band storage, each (2 bw + 1) x n (contiguous:
  !> the callback writes them in place, entry (i, j) at row bw + 1 + i - j); the slots outside the
  !> matrix are zeroed, whatever the callback left there. stat: VCI_OK, VCI_ERR_CALLBACK (code in
  !> work%code) or VCI_ERR_NONFINITE.
  subroutine lagrangian_band_hessians(lag, work, q, v, bw, lqq, lqv, lvv, stat)
    class(vci_lagrangian_t), intent(inout) :: lag
    type(vci_lagrangian_work_t), intent(inout) :: work
    real(dp), intent(in) :: q(:), v(:)
    integer, intent(in) :: bw
    real(dp), intent(inout) :: lqq(:, :), lqv(:, :), lvv(:, :)
    integer, intent(out) :: stat
    integer :: s
    stat = VCI_OK
    s = 0
    call lag%hessians_band(q, v, bw, lqq, lqv, lvv, s)
    if (s /= 0) then
      work%code = s
      stat = VCI_ERR_CALLBACK; return
    end if
    call zero_corners(lqq); call zero_corners(lqv); call zero_corners(lvv)
    if (.not. (finite_matrix(lqq) .and. finite_matrix(lqv) .and. finite_matrix(lvv))) stat = VCI_ERR_NONFINITE
  contains
    !> Rows i = j - bw .. 0 of the first bw columns and i = n + 1 .. j + bw of the last bw (O(bw^2)).
    subroutine zero_corners(ab)
      real(dp), intent(inout) :: ab(:, :)
      integer :: i, j, n
      n = size(ab, 2)
      do j = 1, min(bw, n)
        do i = 1, bw + 1 - j
          ab(i, j) = 0.0_dp
        end do
      end do
      do j = max(1, n - bw + 1), n
        do i = bw + 2 + n - j, 2 * bw + 1
          ab(i, j) = 0.0_dp
        end do
      end do
    end subroutine zero_corners
  end subroutine lagrangian_band_hessians

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

  !> The debug check of a declared bandwidth (check_bandwidth) for a model with hessians_band: at
  !> (q, v) and two points near it, the banded blocks against the dense ones (the model's hessians,
  !> else central differences of dl_dq and dl_dv): a nonzero of the dense blocks outside the band, or
  !> a band entry that differs, fails with why naming the block, the entry and both values.
  !> Tolerance: 1e-10 of the blocks' largest entry (at least 1) against the model's own dense
  !> Hessians (both exact: round-off), 1e-6 against differences (their error, eps^(2/3) relative,
  !> times the third derivatives' size). O(n^2) memory and n^2 callbacks' work: a debug check.
  !> stat: VCI_OK (also when the model has no hessians_band: nothing to check), VCI_ERR_ARGUMENT
  !> (why says which entry), VCI_ERR_CALLBACK or VCI_ERR_NONFINITE (a callback failed: why says so),
  !> VCI_ERR_MEMORY.
  subroutine lagrangian_check_band(lag, q, v, why, stat)
    class(vci_lagrangian_t), intent(inout) :: lag
    real(dp), intent(in) :: q(:), v(:)
    character(len=*), intent(out) :: why
    integer, intent(out) :: stat
    type(vci_lagrangian_work_t) :: band, dense
    real(dp), allocatable :: dq(:, :), dv(:, :), dw(:, :), qk(:), vk(:)
    character(len=3), parameter :: names(3) = ['qq', 'qv', 'vv']
    integer :: n, bw, k, s, i, j, b
    real(dp) :: tol, scale, x, y
    logical :: exact
    why = ''
    n = size(q); bw = lag%hessian_bandwidth
    stat = VCI_OK
    if (bw < 0) return
    call lagrangian_work_setup(band, n, s, band=bw)
    if (s == 0) call lagrangian_work_setup(dense, n, s)
    if (s == 0) allocate (dq(n, n), dv(n, n), dw(n, n), qk(n), vk(n), stat=s)
    if (s /= 0) then
      why = 'cannot allocate the check of the declared bandwidth (out of memory)'
      stat = VCI_ERR_MEMORY; return
    end if
    call lag%clear_not_provided()
    s = 0
    call lag%hessians_band(q, v, bw, band%lqq, band%lqv, band%bvv, s)
    if (lag%answered_not_provided()) then     ! no banded callback: the Newton matrices' check only
      call lag%clear_not_provided(); return
    end if
    call lag%clear_not_provided(); s = 0
    call lag%hessians(q, v, dq, dv, dw, s)
    dense%has_hessians = .not. lag%answered_not_provided()
    call lag%clear_not_provided()
    exact = dense%has_hessians
    do k = 0, 2
      call check_point(q, v, k, qk, vk)
      call lagrangian_band_hessians(lag, band, qk, vk, bw, band%lqq, band%lqv, band%bvv, stat)
      if (stat /= VCI_OK) then
        why = 'hessians_band failed or returned NaN/Inf in the check of the declared bandwidth'
        return
      end if
      call lagrangian_hessians(lag, dense, qk, vk, dq, dv, dw, stat)
      if (stat /= VCI_OK) then
        why = 'the dense Hessians (hessians, or differences of dl_dq and dl_dv) failed or returned NaN/Inf'// &
              ' in the check of the declared bandwidth'
        return
      end if
      do b = 1, 3
        scale = 1.0_dp
        do j = 1, n
          do i = 1, n
            scale = max(scale, abs(block(b, i, j)))
          end do
        end do
        tol = merge(1.0e-10_dp, 1.0e-6_dp, exact) * scale
        do j = 1, n
          do i = 1, n
            y = block(b, i, j)
            if (abs(i - j) > bw) then
              if (abs(y) > tol) then
                write (why, '(a,i0,a,i0,a,es10.3,a,i0,a)') 'L_'//trim(names(b))//'(', i, ', ', j, ') = ', y, &
                  ' lies outside the declared Hessian bandwidth ', bw, ' ('//trim(source())//')'
                stat = VCI_ERR_ARGUMENT; return
              end if
            else
              x = band_entry(b, i, j)
              if (abs(x - y) > tol) then
                write (why, '(a,i0,a,i0,a,es10.3,a,es10.3,a)') 'hessians_band gives L_'//trim(names(b))//'(', i, &
                  ', ', j, ') = ', x, ' where ', y, ' is expected ('//trim(source())//')'
                stat = VCI_ERR_ARGUMENT; return
              end if
            end if
          end do
        end do
      end do
    end do
  contains
    real(dp) function block(b, i, j)
      integer, intent(in) :: b, i, j
      select case (b)
      case (1); block = dq(i, j)
      case (2); block = dv(i, j)
      case default; block = dw(i, j)
      end select
    end function block
    real(dp) function band_entry(b, i, j)
      integer, intent(in) :: b, i, j
      select case (b)
      case (1); band_entry = band%lqq(bw + 1 + i - j, j)
      case (2); band_entry = band%lqv(bw + 1 + i - j, j)
      case default; band_entry = band%bvv(bw + 1 + i - j, j)
      end select
    end function band_entry
    character(len=60) function source()
      if (exact) then
        source = 'the model''s dense hessians'
      else
        source = 'central differences of dl_dq and dl_dv'
      end if
    end function source
  end subroutine lagrangian_check_band

  !> lu(1:bw, :) = 0, lu(bw + 1:3 bw + 1, :) = b: band storage (2 bw + 1 rows) with the rows
  !> band_lu needs for its fill-in.
  pure subroutine fill_in_rows(bw, b, lu)
    integer, intent(in) :: bw
    real(dp), intent(in) :: b(:, :)
    real(dp), intent(inout) :: lu(:, :)
    integer :: i, j
    do j = 1, size(b, 2)
      do i = 1, bw
        lu(i, j) = 0.0_dp
      end do
      do i = 1, 2 * bw + 1
        lu(bw + i, j) = b(i, j)
      end do
    end do
  end subroutine fill_in_rows

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
      if (work%has_sparse_hessians) then    ! (the velocity block's sparse LU by KLU: no n x n array)
        call lagrangian_sparse_hessians(lag, work, lag%hessian_pattern, q, work%w(1:n), work%sqq, work%sqv, &
                                        work%svv, stat)
        if (stat /= VCI_OK) return
        if (.not. all(ieee_is_finite(work%dw(1:n)))) then
          stat = VCI_ERR_NONFINITE; return
        end if
        call work%slu%factor_parts(n, n, lag%hessian_pattern, work%svv, work%none, work%none, work%ones, info)
        if (info /= 0) then
          stat = VCI_ERR_NEWTON; return
        end if
        call work%slu%solve(work%dw(1:n))
      else if (work%has_band_hessians) then      ! (the velocity block's band LU: O(n bw^2), no n x n array)
        ! the velocity block into rows bw + 1 .. 3 bw + 1 of lvv, bw zero rows above it for the fill-in
        call lagrangian_band_hessians(lag, work, q, work%w(1:n), lag%hessian_bandwidth, work%lqq, work%lqv, &
                                      work%bvv, stat)
        if (stat /= VCI_OK) return
        call fill_in_rows(lag%hessian_bandwidth, work%bvv, work%lvv)
        if (.not. all(ieee_is_finite(work%dw(1:n)))) then
          stat = VCI_ERR_NONFINITE; return
        end if
        call band_lu(n, lag%hessian_bandwidth, work%lvv, work%ipiv, info)
        if (info /= 0) then
          stat = VCI_ERR_NEWTON; return
        end if
        call band_solve(n, lag%hessian_bandwidth, work%lvv, work%ipiv, work%dw(1:n))
      else
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
      end if
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
  !> The k-th point (k = 0: (q, v) itself; 1, 2: two points near it, every coordinate moved by up to
  !> 5 k % of its size) where the start-up checks compare a model's Hessian callbacks.
  pure subroutine check_point(q, v, k, qk, vk)
    real(dp), intent(in) :: q(:), v(:)
    integer, intent(in) :: k
    real(dp), intent(out) :: qk(:), vk(:)
    integer :: i
    do i = 1, size(q)
      qk(i) = q(i) + 0.05_dp * k * max(abs(q(i)), 1.0_dp) * sin(1.7_dp * i + k)
      vk(i) = v(i) + 0.05_dp * k * max(abs(v(i)), 1.0_dp) * cos(0.9_dp * i - k)
    end do
  end subroutine check_point

end module vci_lagrangian
