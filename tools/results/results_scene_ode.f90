!> The results scenes as first-order ODEs with events, for the ODE peers (CVODE, the compiled
!> DOP853): state y = (q, qdot), the right-hand side, the gaps (an impact is a decreasing crossing
!> of zero), the elastic frictionless impact map, the energy and, for the nonholonomic pendulum, the
!> constraint residual. Same formulas as the scenes' models and references (vci_results_common).
module results_scene_ode
  use vci_results_common
  implicit none
  private
  public :: state_size, n_roots, scene_rhs, scene_gaps, scene_impact, scene_energy, scene_constraint

contains

  pure integer function state_size(sc)
    integer, intent(in) :: sc
    select case (sc)
    case (SCENE_ELLIPSE); state_size = 6
    case (SCENE_PWALLS); state_size = 2
    case (SCENE_FPU); state_size = 2 * fpu_n
    case default; state_size = 4
    end select
  end function state_size

  pure integer function n_roots(sc)
    integer, intent(in) :: sc
    select case (sc)
    case (SCENE_PWALLS); n_roots = 2
    case (SCENE_FPU); n_roots = 2 * fpu_n
    case default; n_roots = 1
    end select
  end function n_roots

  !> Right-hand side of the scene's first-order system, state (q, qdot).
  subroutine scene_rhs(sc, y, f)
    integer, intent(in) :: sc
    real(rk), intent(in) :: y(:)
    real(rk), intent(out) :: f(:)
    real(rk) :: s, c, ff, dff, ml2, r1, r2
    real(rk) :: r(0:fpu_n), fr(0:fpu_n)
    integer :: n
    select case (sc)
    case (SCENE_PWALLS)
      f = [y(2), -(grav / pw_l) * sin(y(1))]
    case (SCENE_FPU)
      n = fpu_n
      r(0) = y(1); r(1:n - 1) = y(2:n) - y(1:n - 1); r(n) = -y(n)
      fr = r + fpu_beta * r**3
      f(1:n) = y(n + 1:2 * n)
      f(n + 1:2 * n) = fr(1:n) - fr(0:n - 1)
    case (SCENE_PARTICLE)
      f = [y(3), y(4), 0.0_rk, -grav]
    case (SCENE_ELLIPSE)
      f = [y(4), y(5), y(6), 0.0_rk, 0.0_rk, -grav]
    case default
      ! Lagrange-d'Alembert with the multiplier of omega = f dtheta - dphi eliminated
      ! (the same system as tools/reference/references.py, solved in closed form).
      s = sin(y(1)); c = cos(y(1)); ff = pend_f(y(1)); dff = -2.0_rk * s * c
      ml2 = mass * pend_l**2
      r1 = ml2 * y(4)**2 * s * c + mass * grav * pend_l * s
      r2 = -2.0_rk * ml2 * s * c * y(3) * y(4)
      f(1) = y(3); f(2) = y(4)
      f(3) = (r2 - ml2 * s**2 * dff * y(3)**2 + r1 / ff) / (ml2 * (s**2 * ff + 1.0_rk / ff))
      f(4) = ff * f(3) + dff * y(3)**2
    end select
  end subroutine scene_rhs

  subroutine scene_gaps(sc, y, g)
    integer, intent(in) :: sc
    real(rk), intent(in) :: y(:)
    real(rk), intent(out) :: g(:)
    select case (sc)
    case (SCENE_PARTICLE)
      g(1) = y(2)
    case (SCENE_ELLIPSE)
      g(1) = y(3) - sqrt(ell_a**2 * sin(y(1))**2 + ell_b**2 * cos(y(1))**2)
    case (SCENE_PWALLS)
      g(1) = pw_wall - y(1); g(2) = y(1) + pw_wall
    case (SCENE_FPU)
      g(1:fpu_n) = fpu_w - y(1:fpu_n); g(fpu_n + 1:) = fpu_w + y(1:fpu_n)
    case default
      g(1) = pend_r**2 - pend_l**2 * sin(y(1))**2
    end select
  end subroutine scene_gaps

  !> Elastic frictionless impact map; found(j) /= 0 for the gaps that closed.
  subroutine scene_impact(sc, y, found)
    integer, intent(in) :: sc
    real(rk), intent(inout) :: y(:)
    integer, intent(in) :: found(:)
    real(rk) :: n(3), minv(3), mu, phi
    integer :: j, i
    select case (sc)
    case (SCENE_PWALLS)
      y(2) = -y(2)
    case (SCENE_FPU)
      do j = 1, size(found)
        if (found(j) == 0) cycle
        i = mod(j - 1, fpu_n) + 1
        y(fpu_n + i) = -y(fpu_n + i)   ! unit masses, wall normal e_i: v_i reverses
      end do
    case (SCENE_PARTICLE)
      y(4) = -y(4)
    case (SCENE_ELLIPSE)
      phi = sqrt(ell_a**2 * sin(y(1))**2 + ell_b**2 * cos(y(1))**2)
      n = [-(ell_a**2 - ell_b**2) * sin(y(1)) * cos(y(1)) / phi, 0.0_rk, 1.0_rk]
      minv = [4.0_rk / (mass * (ell_a**2 + ell_b**2)), 1.0_rk / mass, 1.0_rk / mass]
      mu = -2.0_rk * dot_product(n, y(4:6)) / dot_product(n, minv * n)
      y(4:6) = y(4:6) + mu * minv * n
    case default
      y(3:4) = -y(3:4)   ! the velocity on the constraint that keeps the energy (docs/DESIGN.md §8)
    end select
  end subroutine scene_impact

  real(rk) function scene_energy(sc, y)
    integer, intent(in) :: sc
    real(rk), intent(in) :: y(:)
    integer :: n
    n = size(y) / 2
    scene_energy = energy_of_velocity(sc, y(1:n), y(n + 1:))
  end function scene_energy

  !> The nonholonomic pendulum's constraint in momentum form over m l^2, sin^2(theta) (f(theta)
  !> thetadot - phidot): the quantity vci's momenta satisfy (p_phi = f sin^2 theta p_theta), finite
  !> through theta = pi; 0 for the holonomic scenes.
  real(rk) function scene_constraint(sc, y) result(r)
    integer, intent(in) :: sc
    real(rk), intent(in) :: y(:)
    r = 0.0_rk
    if (sc == SCENE_PENDULUM) r = sin(y(1))**2 * (pend_f(y(1)) * y(3) - y(4))
  end function scene_constraint
end module results_scene_ode
