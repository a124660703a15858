!> Newton matrices bordered by one row and column (issue 26 item 3, issue 28 item 2): an impact's
!> stage-1 system is the sub-step system A plus the gap row and the alpha column, stage 2's is A plus
!> the energy row and the impulse column. Block elimination with A's own LU factors:
!>
!>     [A  b] [x1]   [r1]     y = A^{-1} r1,  w = A^{-1} b,  s = d - c.w,
!>     [c  d] [x2] = [r2]     x2 = (r2 - c.y) / s,  x1 = y - w x2:
!>
!> one factorisation of A (rows equilibrated by their largest entry, dense LAPACK or the in-line LU
!> below small_max unknowns) and two solves with it, not an LU of the whole matrix. A may be kept
!> from an earlier Newton iteration (a chord on the block) while the border is the current one.
!> `border` refuses (info > 0) when s is below cancel_floor of the terms it is the difference of:
!> then s has lost too many digits and the caller factorises the whole matrix. Nothing non-finite
!> reaches LAPACK (info = -1 instead). Workspace grows on demand (`factor_block`'s stat).
module vci_bordered
  use vci_kinds, only: dp
  use vci_lapack, only: dgetrf, dgetrs
  use vci_kernels, only: small_lu, small_lu_solve, pivots_regular
  implicit none
  private

  !> s = d - c.w with |s| at or below this fraction of |d| + sum |c_i w_i| is refused. s is computed
  !> with an absolute error of about eps cond(A) (|d| + sum |c_i w_i|) (round-off in w and in the
  !> sum), so above the floor x2 is good to about eps cond(A) / 1e-8 = 2e-8 cond(A) relative: a
  !> Newton direction that Newton's next iteration corrects. At or below it the border lies
  !> numerically in A's range (a graze: the wall's normal orthogonal to the motion) and the whole
  !> matrix, factorised with its least-squares fallback, decides.
  real(dp), parameter, public :: cancel_floor = 1.0e-8_dp

  !> LU factors of the block A (n unknowns) and the current border's w = A^{-1} b, c, s.
  type, public :: vci_bordered_t
    integer :: ni = 0                    !< unknowns of the factorised block
    logical :: ready = .false.           !< block factors and a border accepted by `border`
    logical :: block_ok = .false.        !< the block's factors are valid
    real(dp) :: s = 0.0_dp               !< the Schur complement d - c.w
    real(dp), allocatable, private :: lu(:, :), w(:), c(:), rwa(:)
    integer, allocatable, private :: ipiv(:)
    logical, private :: small = .true.
  contains
    !> Factorise the block jac(1:ni, 1:ni) (rows equilibrated); info /= 0: singular or not finite.
    procedure :: factor_block
    !> Take the border column jac(1:ni, ni+1), row jac(ni+1, 1:ni) and corner with the kept block.
    procedure :: border
    !> b(1:ni+1) := the bordered matrix^{-1} b.
    procedure :: solve
  end type vci_bordered_t

contains

  !> Factorise diag(rw) A with A = jac(1:ni, 1:ni) and rw(i) = 1 / max_j |A(i, j)| (the copy is
  !> the module's; jac is not changed). small_max: the in-line LU up to that many unknowns, else
  !> dgetrf. info: 0 done; -1 not finite, no workspace or a zero row; > 0 numerically singular
  !> (a pivot below 1e-14 of the largest, vci_newton's test).
  subroutine factor_block(self, ni, jac, ld, small_max, info)
    class(vci_bordered_t), intent(inout) :: self
    integer, intent(in) :: ni, ld, small_max
    real(dp), intent(in) :: jac(ld, *)
    integer, intent(out) :: info
    integer :: i, j, st
    real(dp) :: big
    self%ready = .false.; self%block_ok = .false.
    info = -1
    call ensure(self, ni, st)
    if (st /= 0 .or. ni < 1) return
    do i = 1, ni
      big = 0.0_dp
      do j = 1, ni
        big = max(big, abs(jac(i, j)))
      end do
      if (.not. (big > 0.0_dp .and. big <= huge(1.0_dp))) return     ! a zero row, or NaN/Inf
      self%rwa(i) = 1.0_dp / big
    end do
    do j = 1, ni
      do i = 1, ni
        self%lu(i, j) = self%rwa(i) * jac(i, j)
      end do
    end do
    self%ni = ni
    self%small = ni <= small_max
    if (self%small) then
      call small_lu(ni, self%lu, self%ipiv, info)
    else
      call dgetrf(ni, ni, self%lu, size(self%lu, 1), self%ipiv, info)
    end if
    if (info /= 0) return
    if (.not. pivots_regular(ni, size(self%lu, 1), self%lu)) then
      info = 1; return
    end if
    self%block_ok = .true.
  end subroutine factor_block

  !> With the kept block factors, take the border of the (ni+1)-matrix jac: b = jac(1:ni, ni+1),
  !> c = jac(ni+1, 1:ni), d = jac(ni+1, ni+1). info: 0 ready; -1 no block factors or not finite;
  !> 1 the Schur complement cancels below cancel_floor (the caller factorises the whole matrix).
  subroutine border(self, jac, ld, info)
    class(vci_bordered_t), intent(inout) :: self
    integer, intent(in) :: ld
    real(dp), intent(in) :: jac(ld, *)
    integer, intent(out) :: info
    integer :: i, ni
    real(dp) :: s, terms
    self%ready = .false.
    info = -1
    if (.not. self%block_ok) return
    ni = self%ni
    do i = 1, ni
      self%w(i) = self%rwa(i) * jac(i, ni + 1)
      self%c(i) = jac(ni + 1, i)
    end do
    if (.not. (finite_sum(self%w(1:ni)) .and. finite_sum(self%c(1:ni)) .and. &
               abs(jac(ni + 1, ni + 1)) <= huge(1.0_dp))) return
    call block_solve(self, self%w)
    s = jac(ni + 1, ni + 1); terms = abs(s)
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
  end subroutine border

  !> b(1:ni+1) := the bordered matrix^{-1} b (after a successful `border`): two block solves in
  !> `border` and here, then the scalar.
  subroutine solve(self, b)
    class(vci_bordered_t), intent(inout) :: self
    real(dp), intent(inout) :: b(:)
    integer :: i, ni
    real(dp) :: x2
    ni = self%ni
    do i = 1, ni
      b(i) = self%rwa(i) * b(i)
    end do
    call block_solve(self, b)
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

  !> v(1:ni) := (diag(rwa) A)^{-1} v with the block's factors.
  subroutine block_solve(self, v)
    type(vci_bordered_t), intent(inout) :: self
    real(dp), intent(inout) :: v(:)
    integer :: info
    if (self%small) then
      call small_lu_solve(self%ni, self%lu, self%ipiv, v)
    else
      call dgetrs('N', self%ni, 1, self%lu, size(self%lu, 1), self%ipiv, v, size(v), info)
    end if
  end subroutine block_solve

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
    if (allocated(self%lu)) then
      if (size(self%lu, 1) >= ni) return
      deallocate (self%lu, self%w, self%c, self%rwa, self%ipiv)
    end if
    allocate (self%lu(ni, ni), self%w(ni), self%c(ni), self%rwa(ni), self%ipiv(ni), stat=st)
    if (st /= 0) then
      if (allocated(self%lu)) deallocate (self%lu)
      if (allocated(self%w)) deallocate (self%w)
      if (allocated(self%c)) deallocate (self%c)
      if (allocated(self%rwa)) deallocate (self%rwa)
      if (allocated(self%ipiv)) deallocate (self%ipiv)
    end if
  end subroutine ensure
end module vci_bordered
