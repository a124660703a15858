!> A Zeno-like sequence (issue 27 item 3): a free particle (L = |v|²/2) in the narrow wedge
!> |q₂| <= k q₁ (walls g₁ = k q₁ - q₂ >= 0, g₂ = k q₁ + q₂ >= 0, half-angle beta = atan k) heading
!> for the apex. Unfolded (each reflection mirrors the plane about the wall), the motion is the
!> straight line q0 + v0 t, and it meets a wall each time its polar angle crosses (2j - 1) beta:
!> about pi / (2 beta) impacts, bunched around the time of closest approach to the apex, the tighter
!> the closer the line passes (impacts accumulating at one time as that distance goes to 0). The
!> exact impact times and the folded state are the reference.
module vci_wedge_case
  use vci
  implicit none
  private

  type, extends(vci_lagrangian_t), public :: wedge_t
    real(dp) :: k = 0.01_dp   !< the walls' slope: |q₂| <= k q₁
  contains
    procedure :: lagrangian, dl_dq, dl_dv, hessians, gaps, gap_gradients, energy
  end type wedge_t

  public :: wedge_model, wedge_impact_times, wedge_exact

contains

  function wedge_model(k) result(model)
    real(dp), intent(in) :: k
    type(wedge_t) :: model
    model%n = 2; model%n_gaps = 2; model%k = k
  end function wedge_model

  subroutine lagrangian(self, q, v, l, stat)
    class(wedge_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: l
    integer, intent(inout) :: stat
    l = 0.5_dp * sum(v**2)
  end subroutine lagrangian

  subroutine dl_dq(self, q, v, out, stat)
    class(wedge_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = 0.0_dp
  end subroutine dl_dq

  subroutine dl_dv(self, q, v, out, stat)
    class(wedge_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = v
  end subroutine dl_dv

  subroutine hessians(self, q, v, lqq, lqv, lvv, stat)
    class(wedge_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: lqq(:, :), lqv(:, :), lvv(:, :)
    integer, intent(inout) :: stat
    lqq = 0.0_dp; lqv = 0.0_dp
    lvv = 0.0_dp; lvv(1, 1) = 1.0_dp; lvv(2, 2) = 1.0_dp
  end subroutine hessians

  subroutine gaps(self, q, g, stat)
    class(wedge_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    g(1) = self%k * q(1) - q(2); g(2) = self%k * q(1) + q(2)
  end subroutine gaps

  subroutine gap_gradients(self, q, dg, stat)
    class(wedge_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    dg(:, 1) = [self%k, -1.0_dp]; dg(:, 2) = [self%k, 1.0_dp]
  end subroutine gap_gradients

  subroutine energy(self, q, p, e, stat)
    class(wedge_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    e = 0.5_dp * sum(p**2)
  end subroutine energy

  !> The impact times of the motion from q0 = (1, 0) with velocity v0 = (-1, b), b > 0: the
  !> unfolded line crosses the ray at angle psi at t = sin psi / (sin psi + b cos psi), for
  !> psi = (2j - 1) beta below the line's limiting angle pi - atan b.
  function wedge_impact_times(k, b) result(times)
    real(dp), intent(in) :: k, b
    real(dp), allocatable :: times(:)
    real(dp) :: beta, psi
    integer :: j
    beta = atan(k)
    allocate (times(0))
    j = 1
    do
      psi = real(2 * j - 1, dp) * beta
      if (psi >= acos(-1.0_dp) - atan(b)) exit
      times = [times, sin(psi) / (sin(psi) + b * cos(psi))]
      j = j + 1
    end do
  end function wedge_impact_times

  !> The exact state at t of that motion: the unfolded point q0 + v0 t lies in the m-th copy of the
  !> wedge (m walls crossed); copy m maps back by the rotation by -2 m beta (m even) or the
  !> reflection about the line at angle m beta (m odd), and so does the velocity.
  subroutine wedge_exact(k, b, t, q, v)
    real(dp), intent(in) :: k, b, t
    real(dp), intent(out) :: q(2), v(2)
    real(dp) :: beta, u(2), w(2), th, c, s
    integer :: m
    beta = atan(k)
    u = [1.0_dp - t, b * t]; w = [-1.0_dp, b]
    m = count(wedge_impact_times(k, b) <= t)
    th = 2.0_dp * real(m, dp) * beta
    c = cos(th); s = sin(th)
    if (mod(m, 2) == 0) then
      q = [c * u(1) + s * u(2), -s * u(1) + c * u(2)]
      v = [c * w(1) + s * w(2), -s * w(1) + c * w(2)]
    else
      q = [c * u(1) + s * u(2), s * u(1) - c * u(2)]
      v = [c * w(1) + s * w(2), s * w(1) - c * w(2)]
    end if
  end subroutine wedge_exact
end module vci_wedge_case
