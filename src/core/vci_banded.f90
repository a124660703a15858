!> Newton matrices with structure (issue 28): a leading block of nb unknowns whose entries vanish
!> outside a band |i - j| <= bw, bordered by nx - nb dense rows and columns (constraint multipliers,
!> the impact fraction alpha or the impulse mu). The block is factorised in LAPACK's band storage
!> (dgbtrf, O(nb bw^2)) and the border by its Schur complement S = D - C A^{-1} B (docs/DESIGN.md,
!> "Structured Newton matrices"):
!>
!>     [A B] [x1]   [r1]      x2 = S^{-1} (r2 - C A^{-1} r1),   x1 = A^{-1} r1 - (A^{-1} B) x2,
!>     [C D] [x2] = [r2]
!>
!> so an impact's stage-1 and stage-2 systems (the sub-step system plus one row and column) cost one
!> band factorisation and nx - nb + 1 band solves, not a dense LU of nx unknowns. The matrix comes
!> row-equilibrated, as vci_newton factorises it; this module never sees a NaN (the caller checks).
!> Workspace is allocated on the first factorisation of a structure (and again only when the
!> structure grows); a failed allocation is reported (the caller then factorises densely).
module vci_banded
  use vci_kinds, only: dp
  use vci_kernels, only: small_lu, small_lu_solve
  implicit none
  private

  interface
    subroutine dgbtrf(m, n, kl, ku, ab, ldab, ipiv, info)
      import :: dp
      integer, intent(in) :: m, n, kl, ku, ldab
      real(dp), intent(inout) :: ab(ldab, *)
      integer, intent(out) :: ipiv(*), info
    end subroutine dgbtrf
    subroutine dgbtrs(trans, n, kl, ku, nrhs, ab, ldab, ipiv, b, ldb, info)
      import :: dp
      character(len=1), intent(in) :: trans
      integer, intent(in) :: n, kl, ku, nrhs, ldab, ldb
      real(dp), intent(in) :: ab(ldab, *)
      integer, intent(in) :: ipiv(*)
      real(dp), intent(inout) :: b(ldb, *)
      integer, intent(out) :: info
    end subroutine dgbtrs
  end interface

  !> Borders up to this size have their Schur complement factorised in line (no LAPACK call).
  integer, parameter :: border_max = 64

  !> Factors of a banded block with a dense border (factor, then solve any number of times).
  type, public :: vci_banded_lu_t
    integer :: nx = 0        !< unknowns of the factorised matrix
    integer :: nb = 0        !< of them, the banded block's
    integer :: bw = 0        !< the block's half-bandwidth
    logical :: ready = .false.  !< factors hold a successful factorisation
    real(dp), allocatable, private :: ab(:, :), w(:, :), c(:, :), s(:, :)
    integer, allocatable, private :: ipiv(:), spiv(:)
  contains
    !> Factorise diag(rw) jac(1:nx, 1:nx) with block nb and half-bandwidth bw.
    procedure :: factor
    !> b(1:nx) := matrix^{-1} b with the factors.
    procedure :: solve
  end type vci_banded_lu_t

  public :: outside_band

contains

  !> Factorise diag(rw) jac(1:nx, 1:nx) (rows scaled as they are copied; jac is not changed) as a band block of nb unknowns (half-bandwidth bw) bordered by nx - nb
  !> dense rows and columns. info: 0 done; > 0 a pivot of the block or of the Schur complement is
  !> zero or negligible (1e-14 of the largest: numerically singular, as vci_newton judges dense LU);
  !> -1 the workspace could not be allocated. The caller falls back to a dense factorisation.
  subroutine factor(self, nx, nb, bw, jac, ld, rw, info)
    class(vci_banded_lu_t), intent(inout) :: self
    integer, intent(in) :: nx, nb, bw, ld
    real(dp), intent(in) :: jac(ld, *), rw(*)
    integer, intent(out) :: info
    integer :: i, j, k, nd, ldab, st
    real(dp) :: acc, dmin, dmax
    self%ready = .false.
    nd = nx - nb
    ldab = 3 * bw + 1
    info = -1
    if (nb < 1 .or. nd < 0 .or. nd > border_max .or. bw < 0) return
    call ensure(self, ldab, nb, nd + 1, st)     ! (+1: a stage system's border after its sub-step's)
    if (st /= 0) return
    self%nx = nx; self%nb = nb; self%bw = bw
    ! band storage: A(i, j) at ab(2 bw + 1 + i - j, j), the top bw rows for dgbtrf's fill-in
    do j = 1, nb
      self%ab(1:bw, j) = 0.0_dp
      do i = max(1, j - bw), min(nb, j + bw)
        self%ab(2 * bw + 1 + i - j, j) = rw(i) * jac(i, j)
      end do
    end do
    call dgbtrf(nb, nb, bw, bw, self%ab, ldab, self%ipiv, info)
    if (info /= 0) return
    dmin = huge(1.0_dp); dmax = 0.0_dp
    do j = 1, nb
      dmin = min(dmin, abs(self%ab(2 * bw + 1, j))); dmax = max(dmax, abs(self%ab(2 * bw + 1, j)))
    end do
    if (.not. dmin > 1.0e-14_dp * dmax) then
      info = 1; return
    end if
    if (nd > 0) then
      ! W = A^{-1} B, S = D - C W
      do k = 1, nd
        do i = 1, nb
          self%w(i, k) = rw(i) * jac(i, nb + k)
        end do
      end do
      call dgbtrs('N', nb, bw, bw, nd, self%ab, ldab, self%ipiv, self%w, nb, info)
      if (info /= 0) return
      do j = 1, nb
        do i = 1, nd
          self%c(i, j) = rw(nb + i) * jac(nb + i, j)
        end do
      end do
      do k = 1, nd
        do i = 1, nd
          acc = rw(nb + i) * jac(nb + i, nb + k)
          do j = 1, nb
            acc = acc - self%c(i, j) * self%w(j, k)
          end do
          self%s(i, k) = acc
        end do
      end do
      dmax = maxval(abs(self%s(1:nd, 1:nd)))
      call small_lu(nd, self%s, self%spiv, info)
      if (info /= 0) return
      dmin = huge(1.0_dp)
      do i = 1, nd
        dmin = min(dmin, abs(self%s(i, i)))
      end do
      ! the Schur complement's pivots against the border's own size (its entries are O(1) after
      ! the rows' equilibration): 1e-14 of that is cancellation to round-off
      if (.not. dmin > 1.0e-14_dp * max(dmax, 1.0_dp)) then
        info = 1; return
      end if
    end if
    info = 0
    self%ready = .true.
  end subroutine factor

  !> b(1:nx) := matrix^{-1} b with the factors of the last successful factor.
  subroutine solve(self, b)
    class(vci_banded_lu_t), intent(inout) :: self
    real(dp), intent(inout) :: b(:)
    integer :: nb, nd, i, j, info
    real(dp) :: acc
    nb = self%nb; nd = self%nx - nb
    call dgbtrs('N', nb, self%bw, self%bw, 1, self%ab, size(self%ab, 1), self%ipiv, b, nb, info)
    if (nd == 0) return
    do i = 1, nd                    ! r2 - C A^{-1} r1
      acc = b(nb + i)
      do j = 1, nb
        acc = acc - self%c(i, j) * b(j)
      end do
      b(nb + i) = acc
    end do
    call small_lu_solve(nd, self%s, self%spiv, b(nb + 1:nb + nd))
    do j = 1, nd                    ! x1 = A^{-1} r1 - W x2
      do i = 1, nb
        b(i) = b(i) - self%w(i, j) * b(nb + j)
      end do
    end do
  end subroutine solve

  !> The first entry (i, j) of the block jac(1:nb, 1:nb) with |i - j| > bw that is not zero (i = 0:
  !> none): a declared band the model's Hessians do not keep.
  pure subroutine outside_band(nb, bw, jac, ld, i, j)
    integer, intent(in) :: nb, bw, ld
    real(dp), intent(in) :: jac(ld, *)
    integer, intent(out) :: i, j
    integer :: ii, jj
    i = 0; j = 0
    do jj = 1, nb
      do ii = 1, nb
        if (abs(ii - jj) > bw .and. jac(ii, jj) /= 0.0_dp) then
          i = ii; j = jj; return
        end if
      end do
    end do
  end subroutine outside_band

  !> Workspace for a block of nb unknowns in band storage of ldab rows and a border of nd.
  subroutine ensure(self, ldab, nb, nd, st)
    type(vci_banded_lu_t), intent(inout) :: self
    integer, intent(in) :: ldab, nb, nd
    integer, intent(out) :: st
    st = 0
    if (allocated(self%ab)) then
      if (size(self%ab, 1) == ldab .and. size(self%ab, 2) == nb .and. size(self%w, 2) >= nd) return
      deallocate (self%ab)
    end if
    if (allocated(self%w)) deallocate (self%w)
    if (allocated(self%c)) deallocate (self%c)
    if (allocated(self%s)) deallocate (self%s)
    if (allocated(self%ipiv)) deallocate (self%ipiv)
    if (allocated(self%spiv)) deallocate (self%spiv)
    allocate (self%ab(ldab, nb), self%w(nb, nd), self%c(nd, nb), self%s(nd, nd), self%ipiv(nb), self%spiv(nd), &
              stat=st)
    if (st /= 0) then
      if (allocated(self%ab)) deallocate (self%ab)
      if (allocated(self%w)) deallocate (self%w)
    end if
  end subroutine ensure
end module vci_banded
