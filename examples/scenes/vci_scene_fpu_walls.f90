!> An FPU-beta chain between walls as a user-written discrete Lagrangian: n unit masses with
!> displacements x_1..x_n, fixed ends x_0 = x_{n+1} = 0, springs V(r) = r^2/2 + beta r^4/4 on the
!> stretches r_j = x_{j+1} - x_j (j = 0..n); midpoint L_d(q, v, h) = h [ |v - q|^2/(2h^2)
!> - V_total((q + v)/2) ]. Walls on every particle, |x_i| <= w: gaps g_i = w - x_i and
!> g_{n+i} = w + x_i (2n of them). Many degrees of freedom, many walls, nonlinear free flight.
!> Reference: test/support/vci_ref_fpu_walls.f90. Used by tools/results.
!> `fpu_walls_lagrangian_t`: the same chain as a continuous model, L = |v|^2/2 - V_total(q), with
!> analytic Hessian blocks (L_qq = -Hess V tridiagonal, L_qv = 0, L_vv = I), for the library's schemes.
module vci_scene_fpu_walls
  use vci, only: dp, vci_model_t, vci_lagrangian_t
  implicit none
  private

  type, extends(vci_model_t), public :: fpu_walls_t
    real(dp) :: beta = 1.0_dp, w = 0.6_dp
  contains
    procedure :: d1, d2, d3, mixed_hessian, gaps, gap_gradients, energy
  end type fpu_walls_t

  type, extends(vci_lagrangian_t), public :: fpu_walls_lagrangian_t
    real(dp) :: beta = 1.0_dp, w = 0.6_dp
    logical :: one_wall_gradient = .true.   !< supply gap_gradient (one wall's gradient, O(n))
    !> supply hessians_band (the blocks in band storage, bandwidth 1); off: "not provided"
    logical :: band_hessians = .false.
    !> supply hessians (the dense blocks); off: "not provided" (the library differences them)
    logical :: dense_hessians = .true.
    integer :: band_calls = 0   !< calls of hessians_band that computed (the tests count them)
    !> a deliberate mistake for the tests of the bandwidth check: L_qq(1, 3) = this (0: none)
    real(dp) :: stray = 0.0_dp
  contains
    procedure :: lagrangian => fl_lagrangian, dl_dq => fl_dl_dq, dl_dv => fl_dl_dv, hessians => fl_hessians
    procedure :: gaps => fl_gaps, gap_gradients => fl_gap_grads, energy => fl_energy
    procedure :: gap_gradient => fl_gap_grad
    procedure :: hessians_band => fl_hessians_band
  end type fpu_walls_lagrangian_t

  public :: fpu_walls_model, fpu_walls_lagrangian_model

contains

  function fpu_walls_model(n, beta, w) result(model)
    integer, intent(in) :: n
    real(dp), intent(in) :: beta, w
    type(fpu_walls_t) :: model
    model%n = n; model%n_gaps = 2 * n
    model%beta = beta; model%w = w
  end function fpu_walls_model

  function fpu_walls_lagrangian_model(n, beta, w) result(model)
    integer, intent(in) :: n
    real(dp), intent(in) :: beta, w
    type(fpu_walls_lagrangian_t) :: model
    model%n = n; model%n_gaps = 2 * n
    model%beta = beta; model%w = w
  end function fpu_walls_lagrangian_model

  !> Stretches r_0..r_n of the chain at x.
  pure function stretches(x) result(r)
    real(dp), intent(in) :: x(:)
    real(dp) :: r(0:size(x))
    integer :: n
    n = size(x)
    r(0) = x(1)
    r(1:n - 1) = x(2:n) - x(1:n - 1)
    r(n) = -x(n)
  end function stretches

  !> Gradient of the potential: dV/dx_i = V'(r_{i-1}) - V'(r_i), V'(r) = r + beta r^3.
  pure function grad_v(self, x) result(gv)
    class(fpu_walls_t), intent(in) :: self
    real(dp), intent(in) :: x(:)
    real(dp) :: gv(size(x))
    gv = potential_gradient(self%beta, x)
  end function grad_v

  pure function potential_gradient(beta, x) result(gv)
    real(dp), intent(in) :: beta, x(:)
    real(dp) :: gv(size(x)), r(0:size(x)), f(0:size(x))
    integer :: n
    n = size(x)
    r = stretches(x)
    f = r + beta * r**3
    gv = f(0:n - 1) - f(1:n)
  end function potential_gradient

  !> Total potential sum_j (r_j^2/2 + beta r_j^4/4).
  pure real(dp) function potential(beta, x) result(v)
    real(dp), intent(in) :: beta, x(:)
    real(dp) :: r(0:size(x))
    r = stretches(x)
    v = sum(0.5_dp * r**2 + 0.25_dp * beta * r**4)
  end function potential

  subroutine d1(self, q, v, h, out, stat)
    class(fpu_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = -(v - q) / h - 0.5_dp * h * grad_v(self, 0.5_dp * (q + v))
  end subroutine d1

  subroutine d2(self, q, v, h, out, stat)
    class(fpu_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = (v - q) / h - 0.5_dp * h * grad_v(self, 0.5_dp * (q + v))
  end subroutine d2

  subroutine d3(self, q, v, h, out, stat)
    class(fpu_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out
    integer, intent(inout) :: stat
    real(dp) :: r(0:size(q))
    r = stretches(0.5_dp * (q + v))
    out = -0.5_dp * sum((v - q)**2) / h**2 - sum(0.5_dp * r**2 + 0.25_dp * self%beta * r**4)
  end subroutine d3

  !> D1 D2 L_d = -I/h - (h/4) Hess V(midpoint), Hess V tridiagonal with K_j = 1 + 3 beta r_j^2.
  subroutine mixed_hessian(self, q, v, h, hess, stat)
    class(fpu_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: hess(:, :)
    integer, intent(inout) :: stat
    real(dp) :: k(0:size(q))
    integer :: i, n
    n = size(q)
    k = 1.0_dp + 3.0_dp * self%beta * stretches(0.5_dp * (q + v))**2
    hess = 0.0_dp
    do i = 1, n
      hess(i, i) = -1.0_dp / h - 0.25_dp * h * (k(i - 1) + k(i))
      if (i < n) then
        hess(i, i + 1) = 0.25_dp * h * k(i)
        hess(i + 1, i) = 0.25_dp * h * k(i)
      end if
    end do
  end subroutine mixed_hessian

  subroutine gaps(self, q, g, stat)
    class(fpu_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    call wall_gaps(self%w, q, g)
  end subroutine gaps

  subroutine gap_gradients(self, q, dg, stat)
    class(fpu_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    call wall_gap_gradients(q, dg)
  end subroutine gap_gradients

  !> H(q, p) = |p|^2/2 + sum_j (r_j^2/2 + beta r_j^4/4).
  subroutine energy(self, q, p, e, stat)
    class(fpu_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    real(dp) :: r(0:size(q))
    r = stretches(q)
    e = 0.5_dp * sum(p**2) + sum(0.5_dp * r**2 + 0.25_dp * self%beta * r**4)
  end subroutine energy

  subroutine fl_lagrangian(self, q, v, l, stat)
    class(fpu_walls_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: l
    integer, intent(inout) :: stat
    l = 0.5_dp * sum(v**2) - potential(self%beta, q)
  end subroutine fl_lagrangian

  subroutine fl_dl_dq(self, q, v, out, stat)
    class(fpu_walls_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = -potential_gradient(self%beta, q)
  end subroutine fl_dl_dq

  subroutine fl_dl_dv(self, q, v, out, stat)
    class(fpu_walls_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = v
  end subroutine fl_dl_dv

  !> L_qq = -Hess V: tridiagonal with K_j = 1 + 3 beta r_j^2 on the springs; L_qv = 0; L_vv = I.
  subroutine fl_hessians(self, q, v, lqq, lqv, lvv, stat)
    class(fpu_walls_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: lqq(:, :), lqv(:, :), lvv(:, :)
    integer, intent(inout) :: stat
    real(dp) :: k(0:size(q))
    integer :: i, n
    lqq = 0.0_dp; lqv = 0.0_dp; lvv = 0.0_dp
    if (.not. self%dense_hessians) then
      call self%not_provided(stat); return
    end if
    n = size(q)
    k = 1.0_dp + 3.0_dp * self%beta * stretches(q)**2
    do i = 1, n
      lqq(i, i) = -(k(i - 1) + k(i))
      if (i < n) then
        lqq(i, i + 1) = k(i)
        lqq(i + 1, i) = k(i)
      end if
      lvv(i, i) = 1.0_dp
    end do
    if (n >= 3) lqq(1, 3) = self%stray
  end subroutine fl_hessians

  !> fl_hessians' blocks in band storage ((2 bw + 1) x n, entry (i, j) at row bw + 1 + i - j):
  !> O(n) numbers where fl_hessians writes 3 n^2. The chain's band is 1; a wider declared band
  !> gets zeros in its outer diagonals.
  subroutine fl_hessians_band(self, q, v, bw, lqq, lqv, lvv, stat)
    class(fpu_walls_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    integer, intent(in) :: bw
    real(dp), intent(out) :: lqq(:, :), lqv(:, :), lvv(:, :)
    integer, intent(inout) :: stat
    real(dp) :: k(0:size(q))
    integer :: i, n
    lqq = 0.0_dp; lqv = 0.0_dp; lvv = 0.0_dp
    if (.not. self%band_hessians) then
      call self%not_provided(stat); return
    end if
    self%band_calls = self%band_calls + 1
    n = size(q)
    k = 1.0_dp + 3.0_dp * self%beta * stretches(q)**2
    do i = 1, n
      lqq(bw + 1, i) = -(k(i - 1) + k(i))
      if (i < n .and. bw >= 1) then   ! (a band of 0 cannot hold them: the tests' mistake)
        lqq(bw, i + 1) = k(i)         ! (i, i + 1)
        lqq(bw + 2, i) = k(i)         ! (i + 1, i)
      end if
      lvv(bw + 1, i) = 1.0_dp
    end do
  end subroutine fl_hessians_band

  subroutine fl_gaps(self, q, g, stat)
    class(fpu_walls_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    call wall_gaps(self%w, q, g)
  end subroutine fl_gaps

  subroutine fl_gap_grads(self, q, dg, stat)
    class(fpu_walls_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    call wall_gap_gradients(q, dg)
  end subroutine fl_gap_grads

  !> One wall's gradient: -e_i for g_i = w - q_i, +e_i for g_{n+i} = w + q_i (O(n), where
  !> gap_gradients fills n x 2n); "not provided" when one_wall_gradient is off (tests compare both).
  subroutine fl_gap_grad(self, q, j, dg, stat)
    class(fpu_walls_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    integer, intent(in) :: j
    real(dp), intent(out) :: dg(:)
    integer, intent(inout) :: stat
    integer :: n
    dg = 0.0_dp
    if (.not. self%one_wall_gradient) then
      call self%not_provided(stat); return
    end if
    n = size(q)
    if (j <= n) then
      dg(j) = -1.0_dp
    else
      dg(j - n) = 1.0_dp
    end if
  end subroutine fl_gap_grad

  !> H(q, p) = |p|^2/2 + V_total(q).
  subroutine fl_energy(self, q, p, e, stat)
    class(fpu_walls_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    e = 0.5_dp * sum(p**2) + potential(self%beta, q)
  end subroutine fl_energy
  !> Both models' walls: g_i = w - q_i and g_{n+i} = w + q_i (each particle between -w and w).
  pure subroutine wall_gaps(w, q, g)
    real(dp), intent(in) :: w, q(:)
    real(dp), intent(out) :: g(:)
    integer :: n
    n = size(q)
    g(1:n) = w - q
    g(n + 1:2 * n) = w + q
  end subroutine wall_gaps

  pure subroutine wall_gap_gradients(q, dg)
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer :: i, n
    n = size(q)
    dg = 0.0_dp
    do i = 1, n
      dg(i, i) = -1.0_dp
      dg(i, n + i) = 1.0_dp
    end do
  end subroutine wall_gap_gradients
end module vci_scene_fpu_walls
