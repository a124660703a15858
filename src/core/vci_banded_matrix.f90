!> A Newton matrix stored in the structure a model declares with a Hessian bandwidth (issue 28
!> item 1): a leading block of nb unknowns that vanishes outside |i - j| <= bw, kept in compact band
!> storage (LAPACK's layout without dgbtrf's fill-in rows: A(i, j) at band(bw + 1 + i - j, j)),
!> and nd = nx - nb dense border rows and columns (the m multipliers, then stage 1's alpha or stage
!> 2's mu) kept apart: rows(k, j) = A(nb + k, j) for the block's columns j <= nb, cols(i, k) =
!> A(i, nb + k) for every row i. So the matrix takes O(nx (2 bw + 1 + 2 nd)) numbers, never nx^2:
!> the scheme writes its Jacobian here (vci_system_t%band_jacobian), vci_banded factorises it from
!> here, and a dense copy is made only for the dense fallback of a singular block (`to_dense`).
!> Space is sized once for the largest system (`size_for`) and a smaller system uses its leading
!> part (nd of them border columns).
module vci_banded_matrix
  use vci_kinds, only: dp
  use vci_kernels, only: invert_row_sizes, border_row_maxima
  implicit none
  private

  !> A band block with a dense border, the unknowns of one posed system (see the module's header).
  type, public :: vci_band_matrix_t
    integer :: nx = 0      !< unknowns of the posed system
    integer :: nb = 0      !< of them, the band block's
    integer :: bw = -1     !< the block's half-bandwidth
    integer :: nd = 0      !< border unknowns, nx - nb
    real(dp), allocatable :: band(:, :)   !< (2 bw + 1, nb): A(i, j) = band(bw + 1 + i - j, j), |i - j| <= bw
    real(dp), allocatable :: rows(:, :)   !< (nd_max, nb): rows(k, j) = A(nb + k, j), j <= nb
    real(dp), allocatable :: cols(:, :)   !< (nx_max, nd_max): cols(i, k) = A(i, nb + k)
  contains
    !> Space for systems of nb block unknowns, half-bandwidth bw and up to nd_max border unknowns.
    procedure :: size_for
    !> Pose a system of nx unknowns (its border: nx - nb) and zero its entries.
    procedure :: pose
    !> The entry A(i, j) (zero outside the band of the block).
    procedure :: at
    !> A(i, j) = v (i, j within the band or the border).
    procedure :: put
    !> Row weights rw(i) = 1 / the largest |A(i, j)| of row i of the leading n x n; returns the sum
    !> of those maxima.
    procedure :: row_weights
    !> The dense a(1:nx, 1:nx) (zeros outside the band): the fallback's copy.
    procedure :: to_dense
  end type vci_band_matrix_t

contains

  !> Allocate for a block of nb unknowns, half-bandwidth bw and up to nd_max border unknowns (kept
  !> when already that size). stat /= 0: out of memory (nothing allocated).
  subroutine size_for(self, nb, bw, nd_max, stat)
    class(vci_band_matrix_t), intent(inout) :: self
    integer, intent(in) :: nb, bw, nd_max
    integer, intent(out) :: stat
    stat = 0
    if (allocated(self%band)) then
      if (size(self%band, 1) == 2 * bw + 1 .and. size(self%band, 2) == nb .and. &
          size(self%rows, 1) >= max(1, nd_max)) return
      deallocate (self%band, self%rows, self%cols)
    end if
    allocate (self%band(2 * bw + 1, nb), self%rows(max(1, nd_max), nb), self%cols(nb + max(1, nd_max), max(1, nd_max)), &
              stat=stat)
    if (stat /= 0) then
      if (allocated(self%band)) deallocate (self%band)
      if (allocated(self%rows)) deallocate (self%rows)
      return
    end if
    self%nb = nb; self%bw = bw; self%nx = 0; self%nd = 0
  end subroutine size_for

  !> Pose a system of nx unknowns (nb <= nx <= nb + nd_max) with every entry zero: O(nx (bw + nd)).
  subroutine pose(self, nx)
    class(vci_band_matrix_t), intent(inout) :: self
    integer, intent(in) :: nx
    integer :: j, nd
    nd = nx - self%nb
    self%nx = nx; self%nd = nd
    ! whole arrays, one contiguous fill each (column by column, a library call per column of 2 bw + 1
    ! numbers was 2 % of the chain's instructions at n = 256); rows beyond nd are not read
    call fill_zero(self%band, size(self%band))
    call fill_zero(self%rows, size(self%rows))
    do j = 1, nd
      self%cols(1:nx, j) = 0.0_dp
    end do
  end subroutine pose

  !> a(1:k) = 0 for an array passed whole (contiguous: one fill, where an assignment to a
  !> component of the class dummy became a strided loop).
  pure subroutine fill_zero(a, k)
    integer, intent(in) :: k
    real(dp), intent(out) :: a(k)
    a = 0.0_dp
  end subroutine fill_zero

  !> A(i, j): zero outside the block's band.
  pure real(dp) function at(self, i, j)
    class(vci_band_matrix_t), intent(in) :: self
    integer, intent(in) :: i, j
    if (j > self%nb) then
      at = self%cols(i, j - self%nb)
    else if (i > self%nb) then
      at = self%rows(i - self%nb, j)
    else if (abs(i - j) <= self%bw) then
      at = self%band(self%bw + 1 + i - j, j)
    else
      at = 0.0_dp
    end if
  end function at

  !> A(i, j) = v; (i, j) in the block outside the band is ignored (its entries are zero by declaration).
  pure subroutine put(self, i, j, v)
    class(vci_band_matrix_t), intent(inout) :: self
    integer, intent(in) :: i, j
    real(dp), intent(in) :: v
    if (j > self%nb) then
      self%cols(i, j - self%nb) = v
    else if (i > self%nb) then
      self%rows(i - self%nb, j) = v
    else if (abs(i - j) <= self%bw) then
      self%band(self%bw + 1 + i - j, j) = v
    end if
  end subroutine put

  !> rw(i) = 1 / the largest |A(i, j)| of row i of the leading nx x nx matrix (nb <= nx <=
  !> self%nx: a stage system's block is the leading part of its matrix) over the band and the
  !> border (1 for a zero row); returns the sum of those maxima (not finite: a NaN or Inf in the
  !> matrix). O(nx (bw + nd)).
  real(dp) function row_weights(self, nx, rw) result(total)
    class(vci_band_matrix_t), intent(in) :: self
    integer, intent(in) :: nx
    real(dp), intent(out) :: rw(:)
    integer :: i, j, nb, bw
    nb = self%nb; bw = self%bw
    rw(1:nx) = 0.0_dp
    do j = 1, nb
      do i = max(1, j - bw), min(nb, j + bw)
        rw(i) = max(rw(i), abs(self%band(bw + 1 + i - j, j)))
      end do
    end do
    call border_row_maxima(nb, nx, self%rows, self%cols, rw)
    call invert_row_sizes(nx, rw, total)
  end function row_weights

  !> a(1:nx, 1:nx) = A, zeros outside the band written: O(nx^2), for the dense fallback only.
  subroutine to_dense(self, a, lda)
    class(vci_band_matrix_t), intent(in) :: self
    integer, intent(in) :: lda
    real(dp), intent(inout) :: a(lda, *)
    integer :: i, j
    do j = 1, self%nx
      do i = 1, self%nx
        a(i, j) = self%at(i, j)
      end do
    end do
  end subroutine to_dense
end module vci_banded_matrix
