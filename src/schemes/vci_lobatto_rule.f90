!> The (s+1)-point Lobatto rule on [0, 1] and the differentiation matrix of its Lagrange basis:
!> nodes c_0 = 0 < c_1 < ... < c_s = 1 (the ends and the roots of P_s'(2c - 1)), weights b_i
!> (exact for polynomials of degree 2s - 1) and D(i, j) = l_j'(c_i), so that a polynomial of degree s
!> through values Y_j has derivative sum_j D(i, j) Y_j at c_i. Computed in double precision by
!> Newton's method on the Legendre recurrence (Chebyshev-Lobatto starting points) and the
!> barycentric formula; test/core/test_schemes.pf checks the weights and the derivatives.
module vci_lobatto_rule
  use vci_kinds, only: dp
  implicit none
  private

  integer, parameter, public :: VCI_LOBATTO_MAX_STAGES = 8  !< the most stages s of the lobatto scheme (order 2s)

  type, public :: vci_lobatto_rule_t
    integer :: s = 0
    real(dp), allocatable :: c(:), b(:), d(:, :)   !< c(0:s), b(0:s), d(0:s, 0:s)
    !> bern(k, i), k, i = 0..s: the Bernstein coefficients of the polynomial of degree s through
    !> values Y_i at the nodes are sum_i bern(k, i) Y_i (issue 25: the poke screen bounds a gap along
    !> the stage polynomial by the least of them, the convex hull property on [0, 1])
    real(dp), allocatable :: bern(:, :)
  end type vci_lobatto_rule_t

  public :: lobatto_rule

contains

  !> The rule with s + 1 points (1 <= s <= VCI_LOBATTO_MAX_STAGES; s = 1 is the trapezoidal rule).
  subroutine lobatto_rule(s, rule, stat)
    integer, intent(in) :: s
    type(vci_lobatto_rule_t), intent(out) :: rule
    integer, intent(out) :: stat
    real(dp), parameter :: pi = acos(-1.0_dp)
    real(dp) :: x(0:s), w(0:s), p, dp1, d2p, dx
    integer :: i, j, it
    stat = 1
    if (s < 1 .or. s > VCI_LOBATTO_MAX_STAGES) return
    allocate (rule%c(0:s), rule%b(0:s), rule%d(0:s, 0:s), rule%bern(0:s, 0:s), stat=stat)
    if (stat /= 0) return
    rule%s = s
    ! nodes on [-1, 1], ascending: the ends and the roots of P_s'
    x(0) = -1.0_dp; x(s) = 1.0_dp
    do i = 1, s - 1
      x(i) = -cos(pi * real(i, dp) / real(s, dp))
      do it = 1, 50
        call legendre(s, x(i), p, dp1, d2p)
        dx = dp1 / d2p
        x(i) = x(i) - dx
        if (abs(dx) <= 2.0_dp * epsilon(1.0_dp)) exit
      end do
    end do
    do i = 0, s
      call legendre(s, x(i), p, dp1, d2p)
      rule%b(i) = 1.0_dp / (real(s * (s + 1), dp) * p**2)    ! 2/(s(s+1)P_s^2) on [-1, 1], halved
      rule%c(i) = 0.5_dp * (x(i) + 1.0_dp)
    end do
    rule%c(0) = 0.0_dp; rule%c(s) = 1.0_dp
    ! symmetric rule: make the computed nodes and weights exactly symmetric
    do i = 0, s / 2
      rule%c(s - i) = 1.0_dp - rule%c(i)
      rule%b(s - i) = rule%b(i)
    end do
    if (mod(s, 2) == 0) rule%c(s / 2) = 0.5_dp
    ! barycentric weights and the differentiation matrix
    do j = 0, s
      w(j) = 1.0_dp
      do i = 0, s
        if (i /= j) w(j) = w(j) / (rule%c(j) - rule%c(i))
      end do
    end do
    do i = 0, s
      rule%d(i, i) = 0.0_dp
      do j = 0, s
        if (i == j) cycle
        rule%d(i, j) = (w(j) / w(i)) / (rule%c(i) - rule%c(j))
        rule%d(i, i) = rule%d(i, i) - rule%d(i, j)
      end do
    end do
    call bernstein_from_nodes(s, rule%c, rule%bern)
    stat = 0
  end subroutine lobatto_rule

  !> w = A^-1 with A(i, k) = binom(s, k) c_i^k (1 - c_i)^(s - k), the Bernstein basis at the nodes
  !> (Gauss-Jordan with partial pivoting; A is well conditioned for s <= 8: the nodes spread over
  !> [0, 1] and include both ends, where A is the identity's first and last rows).
  pure subroutine bernstein_from_nodes(s, c, w)
    integer, intent(in) :: s
    real(dp), intent(in) :: c(0:s)
    real(dp), intent(out) :: w(0:s, 0:s)
    real(dp) :: a(0:s, 0:s), binom, row(0:s)
    integer :: i, k, piv
    do i = 0, s
      binom = 1.0_dp
      do k = 0, s
        a(i, k) = binom * c(i)**k * (1.0_dp - c(i))**(s - k)
        binom = binom * real(s - k, dp) / real(k + 1, dp)
      end do
    end do
    w = 0.0_dp
    do i = 0, s
      w(i, i) = 1.0_dp
    end do
    do k = 0, s
      piv = k - 1 + maxloc(abs(a(k:s, k)), dim=1)
      if (piv /= k) then
        row = a(k, :); a(k, :) = a(piv, :); a(piv, :) = row
        row = w(k, :); w(k, :) = w(piv, :); w(piv, :) = row
      end if
      w(k, :) = w(k, :) / a(k, k); a(k, :) = a(k, :) / a(k, k)
      do i = 0, s
        if (i == k) cycle
        w(i, :) = w(i, :) - a(i, k) * w(k, :)
        a(i, :) = a(i, :) - a(i, k) * a(k, :)
      end do
    end do
  end subroutine bernstein_from_nodes

  !> P_s(x), P_s'(x), P_s''(x) by the three-term recurrence (x inside (-1, 1) for the derivatives;
  !> at x = +-1 the closed values are used).
  pure subroutine legendre(s, x, p, dp1, d2p)
    integer, intent(in) :: s
    real(dp), intent(in) :: x
    real(dp), intent(out) :: p, dp1, d2p
    real(dp) :: pm1, pm2
    integer :: k
    pm1 = 1.0_dp; p = x
    if (s == 0) p = 1.0_dp
    do k = 1, s - 1
      pm2 = pm1; pm1 = p
      p = (real(2 * k + 1, dp) * x * pm1 - real(k, dp) * pm2) / real(k + 1, dp)
    end do
    ! here pm1 = P_{s-1} (for s >= 2)
    if (abs(x) < 1.0_dp) then
      if (s == 1) pm1 = 1.0_dp
      dp1 = real(s, dp) * (x * p - pm1) / (x * x - 1.0_dp)
      d2p = (2.0_dp * x * dp1 - real(s * (s + 1), dp) * p) / (1.0_dp - x * x)
    else
      dp1 = 0.5_dp * real(s * (s + 1), dp) * x**(s + 1)
      d2p = 0.0_dp
    end if
  end subroutine legendre
end module vci_lobatto_rule
