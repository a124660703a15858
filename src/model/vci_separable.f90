!> A separable model: L(q, qdot) = ½ qdotᵀ M qdot − V(q) with a constant, symmetric positive
!> definite mass matrix M (diagonal or dense). The user gives M once (set_mass_diagonal or
!> set_mass_matrix), V, ∇V and, optionally, the Hessian of V; walls (gaps and their gradients) as
!> for any model. It is a continuous model (vci_lagrangian_t: L, ∂L/∂q, ∂L/∂qdot, the Hessian
!> blocks and H are derived here), so every scheme runs it; the explicit compositions
!> (VCI_SCHEME_COMPOSITION, docs/SCHEMES.md) need this kind. Nonholonomic constraints are not part
!> of it: m must stay 0 (the explicit schemes refuse m > 0 with VCI_ERR_ARGUMENT).
module vci_separable
  use vci_kinds, only: dp
  use vci_status, only: VCI_OK, VCI_ERR_ARGUMENT, VCI_ERR_MEMORY
  use vci_lagrangian, only: vci_lagrangian_t
  implicit none
  private

  type, abstract, extends(vci_lagrangian_t), public :: vci_separable_t
    logical :: diagonal_mass = .true.
    real(dp), allocatable :: mass_diag(:), minv_diag(:)   !< M and M⁻¹ when M is diagonal
    real(dp), allocatable :: mass(:, :), minv(:, :)       !< M and M⁻¹ when M is dense
  contains
    procedure(potential_iface), deferred :: potential            !< V(q)
    procedure(gradient_iface), deferred :: potential_gradient    !< ∇V(q)
    procedure :: potential_hessian => not_provided_potential_hessian
    procedure, non_overridable :: set_mass_diagonal
    procedure, non_overridable :: set_mass_matrix
    procedure, non_overridable :: has_mass
    procedure, non_overridable :: inverse_mass_times   !< v = M⁻¹ p
    procedure, non_overridable :: kinetic_energy       !< ½ pᵀ M⁻¹ p
    procedure :: lagrangian => separable_lagrangian
    procedure :: dl_dq => separable_dl_dq
    procedure :: dl_dv => separable_dl_dv
    procedure :: hessians => separable_hessians
    procedure :: energy => separable_energy
  end type vci_separable_t

  abstract interface
    subroutine potential_iface(self, q, v, stat)
      import :: vci_separable_t, dp
      class(vci_separable_t), intent(inout) :: self
      real(dp), intent(in) :: q(:)
      real(dp), intent(out) :: v
      integer, intent(inout) :: stat
    end subroutine potential_iface
    subroutine gradient_iface(self, q, dv, stat)
      import :: vci_separable_t, dp
      class(vci_separable_t), intent(inout) :: self
      real(dp), intent(in) :: q(:)
      real(dp), intent(out) :: dv(:)
      integer, intent(inout) :: stat
    end subroutine gradient_iface
  end interface

contains

  !> d2V/dq2 at q (n x n); optional (else the implicit schemes difference ∂L/∂q).
  subroutine not_provided_potential_hessian(self, q, hv, stat)
    class(vci_separable_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: hv(:, :)
    integer, intent(inout) :: stat
    hv = 0.0_dp
    call self%not_provided(stat)
  end subroutine not_provided_potential_hessian

  !> M = diag(d), every d_i > 0 and finite (else VCI_ERR_ARGUMENT). Set n first.
  subroutine set_mass_diagonal(self, d, stat)
    class(vci_separable_t), intent(inout) :: self
    real(dp), intent(in) :: d(:)
    integer, intent(out) :: stat
    stat = VCI_ERR_ARGUMENT
    if (size(d) /= self%n .or. self%n < 1) return
    if (.not. all(d > 0.0_dp .and. d <= huge(1.0_dp))) return
    if (allocated(self%mass_diag)) deallocate (self%mass_diag, self%minv_diag)
    allocate (self%mass_diag(self%n), self%minv_diag(self%n), stat=stat)
    if (stat /= 0) then
      stat = VCI_ERR_MEMORY; return
    end if
    self%mass_diag = d; self%minv_diag = 1.0_dp / d
    self%diagonal_mass = .true.
    stat = VCI_OK
  end subroutine set_mass_diagonal

  !> A dense M (n x n), symmetric positive definite (else VCI_ERR_ARGUMENT); M⁻¹ is formed once
  !> here from its Cholesky factor, so a step applies it as a product.
  subroutine set_mass_matrix(self, a, stat)
    class(vci_separable_t), intent(inout) :: self
    real(dp), intent(in) :: a(:, :)
    integer, intent(out) :: stat
    real(dp), allocatable :: c(:, :), e(:, :)
    integer :: n, i, j, k
    n = self%n
    stat = VCI_ERR_ARGUMENT
    if (n < 1 .or. size(a, 1) /= n .or. size(a, 2) /= n) return
    if (.not. all(abs(a) <= huge(1.0_dp))) return
    if (any(abs(a - transpose(a)) > 8.0_dp * epsilon(1.0_dp) * maxval(abs(a)))) return
    allocate (c(n, n), e(n, n), stat=stat)
    if (stat /= 0) then
      stat = VCI_ERR_MEMORY; return
    end if
    stat = VCI_ERR_ARGUMENT
    c = 0.0_dp                       ! Cholesky: a = c cᵀ, c lower triangular
    do j = 1, n
      c(j, j) = a(j, j) - sum(c(j, 1:j - 1)**2)
      if (.not. c(j, j) > 0.0_dp) return     ! not positive definite
      c(j, j) = sqrt(c(j, j))
      do i = j + 1, n
        c(i, j) = (a(i, j) - sum(c(i, 1:j - 1) * c(j, 1:j - 1))) / c(j, j)
      end do
    end do
    e = 0.0_dp                       ! columns of M⁻¹: solve c cᵀ x = e_k
    do k = 1, n
      e(k, k) = 1.0_dp
      do i = 1, n
        e(i, k) = (e(i, k) - sum(c(i, 1:i - 1) * e(1:i - 1, k))) / c(i, i)
      end do
      do i = n, 1, -1
        e(i, k) = (e(i, k) - sum(c(i + 1:n, i) * e(i + 1:n, k))) / c(i, i)
      end do
    end do
    if (allocated(self%mass)) deallocate (self%mass, self%minv)
    allocate (self%mass(n, n), self%minv(n, n), stat=stat)
    if (stat /= 0) then
      stat = VCI_ERR_MEMORY; return
    end if
    self%mass = a; self%minv = 0.5_dp * (e + transpose(e))
    self%diagonal_mass = .false.
    stat = VCI_OK
  end subroutine set_mass_matrix

  pure logical function has_mass(self)
    class(vci_separable_t), intent(in) :: self
    if (self%diagonal_mass) then
      has_mass = allocated(self%minv_diag)
    else
      has_mass = allocated(self%minv)
    end if
  end function has_mass

  !> v = M⁻¹ p (the inverse formed once by set_mass_*).
  pure subroutine inverse_mass_times(self, p, v)
    class(vci_separable_t), intent(in) :: self
    real(dp), intent(in) :: p(:)
    real(dp), intent(out) :: v(:)
    integer :: i, n
    n = size(p)
    if (self%diagonal_mass) then
      v(1:n) = self%minv_diag(1:n) * p(1:n)
    else
      do i = 1, n
        v(i) = dot_product(self%minv(i, 1:n), p(1:n))   ! M⁻¹ is symmetric: rows are columns
      end do
    end if
  end subroutine inverse_mass_times

  pure real(dp) function kinetic_energy(self, p) result(t)
    class(vci_separable_t), intent(in) :: self
    real(dp), intent(in) :: p(:)
    integer :: i, n
    n = size(p)
    if (self%diagonal_mass) then
      t = 0.5_dp * sum(self%minv_diag(1:n) * p(1:n)**2)
    else
      t = 0.0_dp
      do i = 1, n
        t = t + p(i) * dot_product(self%minv(i, 1:n), p(1:n))
      end do
      t = 0.5_dp * t
    end if
  end function kinetic_energy

  !> No mass matrix set yet: the callback fails (unrecoverable), never reads unset storage.
  logical function no_mass(self, stat)
    class(vci_separable_t), intent(in) :: self
    integer, intent(inout) :: stat
    no_mass = .not. self%has_mass()
    if (no_mass) stat = -1
  end function no_mass

  !> M v.
  pure subroutine mass_times(self, v, p)
    class(vci_separable_t), intent(in) :: self
    real(dp), intent(in) :: v(:)
    real(dp), intent(out) :: p(:)
    integer :: i, n
    n = size(v)
    if (self%diagonal_mass) then
      p(1:n) = self%mass_diag(1:n) * v(1:n)
    else
      do i = 1, n
        p(i) = dot_product(self%mass(i, 1:n), v(1:n))
      end do
    end if
  end subroutine mass_times

  subroutine separable_lagrangian(self, q, v, l, stat)
    class(vci_separable_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: l
    integer, intent(inout) :: stat
    real(dp) :: pot, mv(size(v))
    l = 0.0_dp
    if (no_mass(self, stat)) return
    call mass_times(self, v, mv)
    call self%potential(q, pot, stat)
    l = 0.5_dp * dot_product(v, mv) - pot
  end subroutine separable_lagrangian

  subroutine separable_dl_dq(self, q, v, out, stat)
    class(vci_separable_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    call self%potential_gradient(q, out, stat)
    out = -out
  end subroutine separable_dl_dq

  subroutine separable_dl_dv(self, q, v, out, stat)
    class(vci_separable_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = 0.0_dp
    if (no_mass(self, stat)) return
    call mass_times(self, v, out)
  end subroutine separable_dl_dv

  !> L_qq = −∇²V (the user's, else "not provided": the implicit schemes difference), L_qv = 0, L_vv = M.
  subroutine separable_hessians(self, q, v, lqq, lqv, lvv, stat)
    class(vci_separable_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: lqq(:, :), lqv(:, :), lvv(:, :)
    integer, intent(inout) :: stat
    integer :: i
    lqq = 0.0_dp; lqv = 0.0_dp; lvv = 0.0_dp
    if (no_mass(self, stat)) return
    call self%potential_hessian(q, lqq, stat)
    lqq = -lqq
    lqv = 0.0_dp
    if (self%diagonal_mass) then
      lvv = 0.0_dp
      do i = 1, size(q)
        lvv(i, i) = self%mass_diag(i)
      end do
    else
      lvv = self%mass
    end if
  end subroutine separable_hessians

  !> H(q, p) = ½ pᵀ M⁻¹ p + V(q).
  subroutine separable_energy(self, q, p, e, stat)
    class(vci_separable_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    real(dp) :: pot
    e = 0.0_dp
    if (no_mass(self, stat)) return
    call self%potential(q, pot, stat)
    e = self%kinetic_energy(p) + pot
  end subroutine separable_energy
end module vci_separable
