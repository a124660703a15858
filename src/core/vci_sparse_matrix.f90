!> A Newton matrix stored in the sparse pattern a model declares (issue 28 items 1 and 3), as
!> vci_banded_matrix stores one in a band: a leading block of nb unknowns whose entries vanish
!> outside the pattern, kept as compressed-column values val(k) of entry (pat%rowind(k), j), and
!> nd = nx - nb dense border rows and columns (the m multipliers, then stage 1's alpha or stage 2's
!> mu) kept apart: rows(k, j) = A(nb + k, j) for the block's columns j <= nb, cols(i, k) =
!> A(i, nb + k) for every row i. So the matrix takes O(nnz + nx nd) numbers, never nx^2: the
!> scheme writes its Jacobian here (vci_system_t%sparse_jacobian), KLU factorises it from here
!> (vci_sparse's factor_parts), and a dense copy is made only for the dense fallback of a singular
!> matrix (`to_dense`). Space is sized once for the largest system (`size_for`) and a smaller
!> system uses its leading part.
module vci_sparse_matrix
  use vci_kinds, only: dp
  use vci_kernels, only: invert_row_sizes, border_row_maxima
  use vci_sparse, only: vci_sparse_pattern_t, pattern_find
  implicit none
  private

  !> A pattern block with a dense border, the unknowns of one posed system (see the module's header).
  type, public :: vci_sparse_matrix_t
    integer :: nx = 0      !< unknowns of the posed system
    integer :: nb = 0      !< of them, the pattern block's
    integer :: nd = 0      !< border unknowns, nx - nb
    type(vci_sparse_pattern_t), pointer :: pat => null()   !< the block's pattern (the model's)
    real(dp), allocatable :: val(:)       !< (nnz): A(pat%rowind(k), j) for colptr(j) <= k < colptr(j + 1)
    real(dp), allocatable :: rows(:, :)   !< (nd_max, nb): rows(k, j) = A(nb + k, j), j <= nb
    real(dp), allocatable :: cols(:, :)   !< (nb + nd_max, nd_max): cols(i, k) = A(i, nb + k)
  contains
    !> Space for the block of pattern pat and up to nd_max border unknowns.
    procedure :: size_for
    !> Pose a system of nx unknowns (its border: nx - nb) and zero its entries.
    procedure :: pose
    !> The entry A(i, j) (zero outside the pattern of the block).
    procedure :: at
    !> Row weights rw(i) = 1 / the largest |A(i, j)| of row i of the leading nx x nx; returns the
    !> sum of those maxima.
    procedure :: row_weights
    !> The dense a(1:nx, 1:nx) (zeros outside the pattern): the fallback's copy.
    procedure :: to_dense
  end type vci_sparse_matrix_t

contains

  !> Allocate for the block of pattern pat (kept by pointer: it must outlive the matrix's use) and
  !> up to nd_max border unknowns (kept when already that size). stat /= 0: out of memory.
  subroutine size_for(self, pat, nd_max, stat)
    class(vci_sparse_matrix_t), intent(inout) :: self
    type(vci_sparse_pattern_t), target, intent(in) :: pat
    integer, intent(in) :: nd_max
    integer, intent(out) :: stat
    integer :: nb, nnz
    stat = 0
    nb = pat%n; nnz = pat%colptr(nb + 1) - 1
    self%pat => pat
    if (allocated(self%val)) then
      if (size(self%val) == nnz .and. self%nb == nb .and. size(self%rows, 1) >= max(1, nd_max)) return
      deallocate (self%val, self%rows, self%cols)
    end if
    allocate (self%val(nnz), self%rows(max(1, nd_max), nb), self%cols(nb + max(1, nd_max), max(1, nd_max)), &
              stat=stat)
    if (stat /= 0) then
      if (allocated(self%val)) deallocate (self%val)
      if (allocated(self%rows)) deallocate (self%rows)
      return
    end if
    self%nb = nb; self%nx = 0; self%nd = 0
  end subroutine size_for

  !> Pose a system of nx unknowns (nb <= nx <= nb + nd_max) with every entry zero: O(nnz + nx nd).
  subroutine pose(self, nx)
    class(vci_sparse_matrix_t), intent(inout) :: self
    integer, intent(in) :: nx
    integer :: j, nd
    nd = nx - self%nb
    self%nx = nx; self%nd = nd
    self%val = 0.0_dp
    do j = 1, self%nb
      self%rows(1:nd, j) = 0.0_dp
    end do
    do j = 1, nd
      self%cols(1:nx, j) = 0.0_dp
    end do
  end subroutine pose

  !> A(i, j): zero outside the block's pattern.
  pure real(dp) function at(self, i, j)
    class(vci_sparse_matrix_t), intent(in) :: self
    integer, intent(in) :: i, j
    integer :: k
    if (j > self%nb) then
      at = self%cols(i, j - self%nb)
    else if (i > self%nb) then
      at = self%rows(i - self%nb, j)
    else
      k = pattern_find(self%pat, i, j)
      at = 0.0_dp
      if (k > 0) at = self%val(k)
    end if
  end function at

  !> rw(i) = 1 / the largest |A(i, j)| of row i of the leading nx x nx matrix (nb <= nx <=
  !> self%nx: a stage system's block is the leading part of its matrix) over the pattern and the
  !> border (1 for a zero row); returns the sum of those maxima (not finite: a NaN or Inf in the
  !> matrix). O(nnz + nx nd).
  real(dp) function row_weights(self, nx, rw) result(total)
    class(vci_sparse_matrix_t), intent(in) :: self
    integer, intent(in) :: nx
    real(dp), intent(out) :: rw(:)
    integer :: i, j, k, nb
    nb = self%nb
    rw(1:nx) = 0.0_dp
    do j = 1, nb
      do k = self%pat%colptr(j), self%pat%colptr(j + 1) - 1
        i = self%pat%rowind(k)
        rw(i) = max(rw(i), abs(self%val(k)))
      end do
    end do
    call border_row_maxima(nb, nx, self%rows, self%cols, rw)
    call invert_row_sizes(nx, rw, total)
  end function row_weights

  !> a(1:nx, 1:nx) = A, zeros outside the pattern written: O(nx^2), for the dense fallback only.
  subroutine to_dense(self, a, lda)
    class(vci_sparse_matrix_t), intent(in) :: self
    integer, intent(in) :: lda
    real(dp), intent(inout) :: a(lda, *)
    integer :: i, j, k, nb
    nb = self%nb
    do j = 1, self%nx
      a(1:self%nx, j) = 0.0_dp
      if (j <= nb) then
        do k = self%pat%colptr(j), self%pat%colptr(j + 1) - 1
          a(self%pat%rowind(k), j) = self%val(k)
        end do
        do i = nb + 1, self%nx
          a(i, j) = self%rows(i - nb, j)
        end do
      else
        do i = 1, self%nx
          a(i, j) = self%cols(i, j - nb)
        end do
      end if
    end do
  end subroutine to_dense
end module vci_sparse_matrix
