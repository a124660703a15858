!> Newton matrices bordered by one row and column (issue 26 item 3, issue 28 item 2): an impact's
!> stage-1 system is the sub-step system A plus the gap row and the alpha column, stage 2's is A plus
!> the energy row and the impulse column. Block elimination with A's own factors, of whatever kind
!> A declares (vci_factor: dense LU, a band with its own dense border, a sparse pattern by KLU):
!>
!>     [A  b] [x1]   [r1]     y = A^{-1} r1,  w = A^{-1} b,  s = d - c.w,
!>     [c  d] [x2] = [r2]     x2 = (r2 - c.y) / s,  x1 = y - w x2:
!>
!> one factorisation of A (rows equilibrated by the caller, who passes the weights) and two solves
!> with it, not a factorisation of the whole matrix. A may be kept from an earlier Newton iteration
!> (a chord on the block) while the border is the current one. `border` refuses (info > 0) when s
!> is below cancel_floor of the terms it is the difference of: then s has lost too many digits and
!> the caller factorises the whole matrix. Workspace grows on demand.
module vci_bordered
  use vci_kinds, only: dp
  use vci_factor, only: vci_factor_t
  implicit none
  private

  !> s = d - c.w with |s| at or below this fraction of |d| + sum |c_i w_i| is refused. s is computed
  !> with an absolute error of about eps cond(A) (|d| + sum |c_i w_i|) (round-off in w and in the
  !> sum), so above the floor x2 is good to about eps cond(A) / 1e-8 = 2e-8 cond(A) relative: a
  !> Newton direction that Newton's next iteration corrects. At or below it the border lies
  !> numerically in A's range (a graze: the wall's normal orthogonal to the motion) and the whole
  !> matrix, factorised with its least-squares fallback, decides.
  real(dp), parameter, public :: cancel_floor = 1.0e-8_dp

  !> The current border of a factorised block A (ni unknowns): w = A^{-1} b, c, s, A's row weights.
  type, public :: vci_bordered_t
    integer :: ni = 0                    !< unknowns of the block
    logical :: ready = .false.           !< a border accepted by `border` (solve uses it)
    real(dp) :: s = 0.0_dp               !< the Schur complement d - c.w
    real(dp), allocatable, private :: w(:), c(:), rwa(:)
  contains
    !> Take the border column jac(1:ni, ni+1), row jac(ni+1, 1:ni) and corner with the block's factors.
    procedure :: border
    !> The same with the border column, row and corner given apart.
    procedure :: border_parts
    !> b(1:ni+1) := the bordered matrix^{-1} b.
    procedure :: solve
  end type vci_bordered_t

contains

  !> With blk the factors of diag(rw) A, A = jac(1:ni, 1:ni), take the border of the (ni+1)-matrix
  !> jac: b = jac(1:ni, ni+1), c = jac(ni+1, 1:ni), d = jac(ni+1, ni+1). info: 0 ready; -1 no block
  !> factors, no workspace or not finite; 1 the Schur complement cancels below cancel_floor (the
  !> caller factorises the whole matrix).
  subroutine border(self, blk, ni, jac, ld, rw, info)
    class(vci_bordered_t), intent(inout) :: self
    class(vci_factor_t), intent(inout) :: blk
    integer, intent(in) :: ni, ld
    real(dp), intent(in) :: jac(ld, *), rw(*)
    integer, intent(out) :: info
    call self%border_parts(blk, ni, jac(1:ni, ni + 1), jac(ni + 1, 1:ni), jac(ni + 1, ni + 1), rw, info)
  end subroutine border

  !> border with the border given as its parts: column b(1:ni), row c(1:ni), corner d (a matrix
  !> stored in its structure, vci_banded_matrix, keeps them apart; no n x n array).
  subroutine border_parts(self, blk, ni, b, c, d, rw, info)
    class(vci_bordered_t), intent(inout) :: self
    class(vci_factor_t), intent(inout) :: blk
    integer, intent(in) :: ni
    real(dp), intent(in) :: b(:), c(:), d, rw(*)
    integer, intent(out) :: info
    integer :: i, st
    real(dp) :: s, terms
    self%ready = .false.
    info = -1
    if (.not. blk%ready .or. ni < 1) return
    call ensure(self, ni, st)
    if (st /= 0) return
    self%ni = ni
    do i = 1, ni
      self%rwa(i) = rw(i)
      self%w(i) = rw(i) * b(i)
      self%c(i) = c(i)
    end do
    if (.not. (finite_sum(self%w(1:ni)) .and. finite_sum(self%c(1:ni)) .and. &
               abs(d) <= huge(1.0_dp))) return
    call blk%solve(self%w(1:ni))
    s = d; terms = abs(s)
    do i = 1, ni
      s = s - self%c(i) * self%w(i)
      terms = terms + abs(self%c(i) * self%w(i))
    end do
    if (.not. (abs(s) <= huge(1.0_dp) .and. terms <= huge(1.0_dp))) return
    info = 1
    if (.not. abs(s) > cancel_floor * terms) return
    self%s = s
    info = 0
    self%ready = .true.
  end subroutine border_parts

  !> b(1:ni+1) := the bordered matrix^{-1} b (after a successful `border` with the same blk): the
  !> block solve, then the scalar.
  subroutine solve(self, blk, b)
    class(vci_bordered_t), intent(inout) :: self
    class(vci_factor_t), intent(inout) :: blk
    real(dp), intent(inout) :: b(:)
    integer :: i, ni
    real(dp) :: x2
    ni = self%ni
    do i = 1, ni
      b(i) = self%rwa(i) * b(i)
    end do
    call blk%solve(b(1:ni))
    x2 = b(ni + 1)
    do i = 1, ni
      x2 = x2 - self%c(i) * b(i)
    end do
    x2 = x2 / self%s
    do i = 1, ni
      b(i) = b(i) - self%w(i) * x2
    end do
    b(ni + 1) = x2
  end subroutine solve

  pure logical function finite_sum(a)
    real(dp), intent(in) :: a(:)
    integer :: i
    real(dp) :: t
    t = 0.0_dp
    do i = 1, size(a)
      t = t + abs(a(i))
    end do
    finite_sum = t <= huge(1.0_dp)
  end function finite_sum

  !> Workspace for a block of ni unknowns (kept when large enough).
  subroutine ensure(self, ni, st)
    type(vci_bordered_t), intent(inout) :: self
    integer, intent(in) :: ni
    integer, intent(out) :: st
    st = 0
    if (allocated(self%w)) then
      if (size(self%w) >= ni) return
      deallocate (self%w, self%c, self%rwa)
    end if
    allocate (self%w(ni), self%c(ni), self%rwa(ni), stat=st)
    if (st /= 0) then
      if (allocated(self%w)) deallocate (self%w)
      if (allocated(self%c)) deallocate (self%c)
      if (allocated(self%rwa)) deallocate (self%rwa)
    end if
  end subroutine ensure
end module vci_bordered
