!> Newton matrices with structure (issue 28): a leading block of nb unknowns whose entries vanish
!> outside a band |i - j| <= bw, bordered by nx - nb dense rows and columns (constraint multipliers,
!> the impact fraction alpha or the impulse mu). The block is factorised in LAPACK's band storage
!> (partial pivoting as dgbtrf, O(nb bw^2), in line: for bw = 1 LAPACK's per-column BLAS calls cost
!> several times the arithmetic, a quarter of a chain's impact step at n = 128) and the border by its Schur complement S = D - C A^{-1} B (docs/DESIGN.md,
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
  use vci_factor, only: vci_factor_t
  use vci_banded_matrix, only: vci_band_matrix_t
  implicit none
  private


  !> Borders up to this size have their Schur complement factorised in line (no LAPACK call).
  integer, parameter :: border_max = 64

  !> Factors of a banded block with a dense border (factor, then solve any number of times).
  type, extends(vci_factor_t), public :: vci_banded_lu_t
    integer :: nx = 0        !< unknowns of the factorised matrix
    integer :: nb = 0        !< of them, the banded block's
    integer :: bw = 0        !< the block's half-bandwidth
    real(dp), allocatable, private :: ab(:, :), w(:, :), c(:, :), s(:, :)
    integer, allocatable, private :: ipiv(:), spiv(:)
  contains
    !> Factorise diag(rw) jac(1:nx, 1:nx) with block nb and half-bandwidth bw.
    procedure :: factor
    !> The same from a matrix stored in its structure (vci_band_matrix_t), no n x n array.
    procedure :: factor_packed
    !> b(1:nx) := matrix^{-1} b with the factors.
    procedure :: solve
  end type vci_banded_lu_t

  public :: outside_band
  !> The band block's own LU and solve (also the banded Legendre inversion's, vci_lagrangian).
  public :: band_lu, band_solve

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
    integer :: i, j, k, nd
    call take_sizes(self, nx, nb, bw, info)
    if (info /= 0) return
    nd = nx - nb
    ! band storage: A(i, j) at ab(2 bw + 1 + i - j, j), the top bw rows for dgbtrf's fill-in
    do j = 1, nb
      self%ab(1:bw, j) = 0.0_dp
      do i = max(1, j - bw), min(nb, j + bw)
        self%ab(2 * bw + 1 + i - j, j) = rw(i) * jac(i, j)
      end do
    end do
    do k = 1, nd
      do i = 1, nb
        self%w(i, k) = rw(i) * jac(i, nb + k)
      end do
    end do
    do j = 1, nb
      do i = 1, nd
        self%c(i, j) = rw(nb + i) * jac(nb + i, j)
      end do
    end do
    do k = 1, nd
      do i = 1, nd
        self%s(i, k) = rw(nb + i) * jac(nb + i, nb + k)
      end do
    end do
    call factor_taken(self, info)
  end subroutine factor

  !> factor, with the matrix in its declared structure (vci_banded_matrix: compact band, border
  !> rows and columns apart), of nx unknowns: its leading nx (<= mat%nx) rows and columns, so a
  !> stage system's block (the sub-step's unknowns) is factorised from the stage's own matrix.
  !> Nothing of size nx^2 is read or written.
  subroutine factor_packed(self, nx, mat, rw, info)
    class(vci_banded_lu_t), intent(inout) :: self
    integer, intent(in) :: nx
    type(vci_band_matrix_t), intent(in) :: mat
    real(dp), intent(in) :: rw(*)
    integer, intent(out) :: info
    integer :: i, j, k, nd, nb, bw
    nb = mat%nb; bw = mat%bw
    info = -1
    if (nx > mat%nx) return
    call take_sizes(self, nx, nb, bw, info)
    if (info /= 0) return
    nd = nx - nb
    ! the fill rows zero: the whole columns in one contiguous fill (row 1:bw column by column was
    ! a library call per column)
    self%ab(:, 1:nb) = 0.0_dp
    do j = 1, nb
      do i = max(1, j - bw), min(nb, j + bw)
        self%ab(2 * bw + 1 + i - j, j) = rw(i) * mat%band(bw + 1 + i - j, j)
      end do
    end do
    do k = 1, nd
      do i = 1, nb
        self%w(i, k) = rw(i) * mat%cols(i, k)
      end do
    end do
    do j = 1, nb
      do i = 1, nd
        self%c(i, j) = rw(nb + i) * mat%rows(i, j)
      end do
    end do
    do k = 1, nd
      do i = 1, nd
        self%s(i, k) = rw(nb + i) * mat%cols(nb + i, k)
      end do
    end do
    call factor_taken(self, info)
  end subroutine factor_packed

  !> Check the sizes and make room for them (info -1: a border above border_max, or no memory).
  subroutine take_sizes(self, nx, nb, bw, info)
    type(vci_banded_lu_t), intent(inout) :: self
    integer, intent(in) :: nx, nb, bw
    integer, intent(out) :: info
    integer :: nd, st
    self%ready = .false.
    nd = nx - nb
    info = -1
    if (nb < 1 .or. nd < 0 .or. nd > border_max .or. bw < 0) return
    call ensure(self, 3 * bw + 1, nb, nd + 1, st)     ! (+1: a stage system's border after its sub-step's)
    if (st /= 0) return
    self%nx = nx; self%nb = nb; self%bw = bw
    info = 0
  end subroutine take_sizes

  !> The factorisation of what factor or factor_packed put in ab (the scaled band, fill rows zero),
  !> w (B), c (C) and s (D): the band LU, W = A^{-1} B and the Schur complement S = D - C W.
  subroutine factor_taken(self, info)
    type(vci_banded_lu_t), intent(inout) :: self
    integer, intent(out) :: info
    integer :: i, j, k, nd, nb, bw
    real(dp) :: acc, dmin, dmax
    nb = self%nb; bw = self%bw; nd = self%nx - nb
    call band_lu(nb, bw, self%ab, self%ipiv, info)
    if (info /= 0) return
    dmin = huge(1.0_dp); dmax = 0.0_dp
    do j = 1, nb
      dmin = min(dmin, abs(self%ab(2 * bw + 1, j))); dmax = max(dmax, abs(self%ab(2 * bw + 1, j)))
    end do
    if (.not. dmin > 1.0e-14_dp * dmax) then
      info = 1; return
    end if
    if (nd > 0) then
      do k = 1, nd
        call band_solve(nb, bw, self%ab, self%ipiv, self%w(:, k))
      end do
      do k = 1, nd
        do i = 1, nd
          acc = self%s(i, k)
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
  end subroutine factor_taken

  !> b(1:nx) := matrix^{-1} b with the factors of the last successful factor.
  subroutine solve(self, b)
    class(vci_banded_lu_t), intent(inout) :: self
    real(dp), intent(inout) :: b(:)
    integer :: nb, nd, i, j
    real(dp) :: acc
    nb = self%nb; nd = self%nx - nb
    call band_solve(nb, self%bw, self%ab, self%ipiv, b)
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

  !> LU with partial pivoting of the n x n band matrix (kl = ku = bw) in ab (LAPACK's band storage,
  !> A(r, c) = ab(2 bw + 1 + r - c, c), with bw rows for the fill-in, zero on entry); ipiv and info as
  !> dgbtrf's. The pivot is the first largest |entry| of the column, as idamax picks it.
  pure subroutine band_lu(n, bw, ab, ipiv, info)
    integer, intent(in) :: n, bw
    real(dp), intent(inout) :: ab(:, :)
    integer, intent(out) :: ipiv(:), info
    integer :: j, c, r, km, jp, ju, kv, p
    real(dp) :: t, big
    kv = 2 * bw
    info = 0
    ju = 1
    do j = 1, n
      km = min(bw, n - j)
      jp = 0; big = -1.0_dp
      do r = 0, km
        if (abs(ab(kv + 1 + r, j)) > big) then
          big = abs(ab(kv + 1 + r, j)); jp = r
        end if
      end do
      ipiv(j) = j + jp
      if (ab(kv + 1 + jp, j) == 0.0_dp) then
        if (info == 0) info = j
        cycle
      end if
      ju = max(ju, min(j + bw + jp, n))     ! the last column the pivot row reaches
      if (jp /= 0) then                     ! swap rows j and j + jp over columns j .. ju
        p = j + jp
        do c = j, ju
          t = ab(kv + 1 + p - c, c); ab(kv + 1 + p - c, c) = ab(kv + 1 + j - c, c); ab(kv + 1 + j - c, c) = t
        end do
      end if
      if (km > 0) then
        t = 1.0_dp / ab(kv + 1, j)
        do r = 1, km
          ab(kv + 1 + r, j) = ab(kv + 1 + r, j) * t
        end do
        do c = j + 1, ju
          t = ab(kv + 1 + j - c, c)
          if (t /= 0.0_dp) then
            do r = 1, km
              ab(kv + 1 + j + r - c, c) = ab(kv + 1 + j + r - c, c) - ab(kv + 1 + r, j) * t
            end do
          end if
        end do
      end if
    end do
  end subroutine band_lu

  !> b := A^{-1} b with band_lu's factors (as dgbtrs 'N' with one right-hand side).
  pure subroutine band_solve(n, bw, ab, ipiv, b)
    integer, intent(in) :: n, bw
    real(dp), intent(in) :: ab(:, :)
    integer, intent(in) :: ipiv(:)
    real(dp), intent(inout) :: b(:)
    integer :: j, i, lm, l, kv
    real(dp) :: t
    kv = 2 * bw
    do j = 1, n - 1                  ! L, with the row interchanges
      lm = min(bw, n - j)
      l = ipiv(j)
      if (l /= j) then
        t = b(l); b(l) = b(j); b(j) = t
      end if
      t = b(j)
      do i = 1, lm
        b(j + i) = b(j + i) - ab(kv + 1 + i, j) * t
      end do
    end do
    do j = n, 1, -1                  ! U: upper band of width 2 bw
      b(j) = b(j) / ab(kv + 1, j)
      t = b(j)
      do i = max(1, j - kv), j - 1
        b(i) = b(i) - ab(kv + 1 + i - j, j) * t
      end do
    end do
  end subroutine band_solve

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
