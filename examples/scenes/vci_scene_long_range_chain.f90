!> The FPU-beta chain between walls (vci_scene_fpu_walls) with long-range linear springs of
!> stiffness kl between particles i and i + offset: every Hessian row has at most 5 nonzeros
!> (offsets 0, +-1, +-offset), but the band that holds them has half-width offset. The model can
!> declare that sparse pattern (declare_long_range_pattern) and give its Hessian blocks in it
!> (hessians_sparse, issue 28): the tests and bench/sparse_chain.f90 run it dense, banded and sparse.
module vci_scene_long_range_chain
  use vci, only: dp
  use vci_scene_fpu_walls, only: fpu_walls_lagrangian_t
  implicit none
  private

  !> The FPU chain plus springs (i, i + offset) of stiffness kl.
  type, extends(fpu_walls_lagrangian_t), public :: long_range_chain_t
    integer :: offset = 1
    real(dp) :: kl = 0.5_dp
    !> supply hessians_sparse (the blocks in the declared pattern); off: "not provided"
    logical :: sparse_hessians = .true.
    integer :: sparse_calls = 0             !< calls of hessians_sparse that computed
    integer, allocatable :: colptr(:), rowind(:)   !< the pattern declare_long_range_pattern declared
  contains
    procedure :: lagrangian => lr_lagrangian, dl_dq => lr_dl_dq, hessians => lr_hessians, energy => lr_energy
    procedure :: hessians_sparse => lr_hessians_sparse
    !> Declare the pattern of offsets 0, +-1, +-offset (both triangles, rows sorted).
    procedure :: declare_long_range_pattern
  end type long_range_chain_t

contains

  real(dp) function lr_potential(self, q) result(v)
    class(long_range_chain_t), intent(in) :: self
    real(dp), intent(in) :: q(:)
    integer :: l, n
    n = size(q); l = self%offset
    v = 0.5_dp * self%kl * sum((q(1 + l:n) - q(1:n - l))**2)
  end function lr_potential

  subroutine lr_lagrangian(self, q, v, l, stat)
    class(long_range_chain_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: l
    integer, intent(inout) :: stat
    call self%fpu_walls_lagrangian_t%lagrangian(q, v, l, stat)
    l = l - lr_potential(self, q)
  end subroutine lr_lagrangian

  subroutine lr_energy(self, q, p, e, stat)
    class(long_range_chain_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    call self%fpu_walls_lagrangian_t%energy(q, p, e, stat)
    e = e + lr_potential(self, q)
  end subroutine lr_energy

  subroutine lr_dl_dq(self, q, v, out, stat)
    class(long_range_chain_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    integer :: i, l, n
    real(dp) :: d
    call self%fpu_walls_lagrangian_t%dl_dq(q, v, out, stat)
    n = size(q); l = self%offset
    do i = 1, n - l
      d = self%kl * (q(i + l) - q(i))
      out(i) = out(i) + d; out(i + l) = out(i + l) - d
    end do
  end subroutine lr_dl_dq

  !> The dense blocks: the chain's (when fpu_walls' dense_hessians is on) plus the springs'.
  subroutine lr_hessians(self, q, v, lqq, lqv, lvv, stat)
    class(long_range_chain_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: lqq(:, :), lqv(:, :), lvv(:, :)
    integer, intent(inout) :: stat
    integer :: i, l, n
    call self%fpu_walls_lagrangian_t%hessians(q, v, lqq, lqv, lvv, stat)
    if (.not. self%dense_hessians) return
    n = size(q); l = self%offset
    do i = 1, n - l
      lqq(i, i) = lqq(i, i) - self%kl; lqq(i + l, i + l) = lqq(i + l, i + l) - self%kl
      lqq(i, i + l) = lqq(i, i + l) + self%kl; lqq(i + l, i) = lqq(i + l, i) + self%kl
    end do
  end subroutine lr_hessians

  !> The blocks in the declared pattern's order (colptr, rowind): L_qq = -Hess V, L_qv = 0,
  !> L_vv = I. O(nnz).
  subroutine lr_hessians_sparse(self, q, v, lqq, lqv, lvv, stat)
    class(long_range_chain_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: lqq(:), lqv(:), lvv(:)
    integer, intent(inout) :: stat
    real(dp) :: k(0:size(q)), r
    integer :: i, j, p, n, l
    lqq = 0.0_dp; lqv = 0.0_dp; lvv = 0.0_dp
    if (.not. self%sparse_hessians) then
      call self%not_provided(stat); return
    end if
    self%sparse_calls = self%sparse_calls + 1
    n = size(q); l = self%offset
    ! K_j = 1 + 3 beta r_j^2 on the nearest-neighbour springs, r_0 = q_1, r_j = q_{j+1} - q_j, r_n = -q_n
    do j = 0, n
      if (j == 0) then
        r = q(1)
      else if (j == n) then
        r = -q(n)
      else
        r = q(j + 1) - q(j)
      end if
      k(j) = 1.0_dp + 3.0_dp * self%beta * r**2
    end do
    do j = 1, n
      do p = self%colptr(j), self%colptr(j + 1) - 1
        i = self%rowind(p)
        if (i == j) then
          lqq(p) = -(k(i - 1) + k(i))
          if (i + l <= n) lqq(p) = lqq(p) - self%kl
          if (i - l >= 1) lqq(p) = lqq(p) - self%kl
          lvv(p) = 1.0_dp
        else
          if (abs(i - j) == 1) lqq(p) = k(min(i, j))
          if (abs(i - j) == l) lqq(p) = lqq(p) + self%kl
        end if
      end do
    end do
  end subroutine lr_hessians_sparse

  !> Declare (check: the debug check) the pattern of offsets 0, +-1, +-offset, both triangles,
  !> each column's rows sorted; kept in colptr, rowind for hessians_sparse.
  subroutine declare_long_range_pattern(self, check)
    class(long_range_chain_t), intent(inout) :: self
    logical, intent(in) :: check
    integer :: offs(5), j, d, q, n
    n = self%n
    offs = [-self%offset, -1, 0, 1, self%offset]
    if (self%offset == 1) offs = [-1, -1, 0, 1, 1]
    if (allocated(self%colptr)) deallocate (self%colptr, self%rowind)
    allocate (self%colptr(n + 1), self%rowind(5 * n))
    q = 0
    do j = 1, n
      self%colptr(j) = q + 1
      do d = 1, 5
        if (d > 1) then
          if (offs(d) == offs(d - 1)) cycle
        end if
        if (j + offs(d) >= 1 .and. j + offs(d) <= n) then
          q = q + 1; self%rowind(q) = j + offs(d)
        end if
      end do
    end do
    self%colptr(n + 1) = q + 1
    call self%declare_pattern(self%colptr, self%rowind(1:q), check=check)
  end subroutine declare_long_range_pattern
end module vci_scene_long_range_chain
