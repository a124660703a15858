!> Exact reference for the planar pendulum, free or between elastic walls (an impact oscillator).
!> Independent of the vci library: only iso_fortran_env. Everything is computed in quad precision
!> (real128) from the double inputs taken as exact; the double interface rounds the results once.
!>
!> Model. L = ½mℓ²θ̇² + mgℓ cosθ, so θ̈ = −ω₀² sinθ with ω₀ = sqrt(g/ℓ) and θ = 0 hanging down;
!> energy E = ½mℓ²θ̇² − mgℓ cosθ. Walls (when 0 < θ_w < π): admissible set |θ| ≤ θ_w, elastic
!> impact θ̇ → −θ̇ on reaching |θ| = θ_w.
!>
!> Modulus. With y = θ̇/(2ω₀), s = sin(θ/2), c = cos(θ/2) the invariant is k² = y² + s²
!> (k = sin(θ_max/2) for libration). Libration k < 1, separatrix k = 1, rotation k > 1.
!> Elliptic functions take the modulus k (not the parameter m = k²).
!>   libration: sin(θ/2) = k sn(u, k), θ̇ = 2kω₀ cn(u, k), u = u₀ + ω₀t, period 4K(k)/ω₀;
!>   separatrix: θ = 2 atan(sinh u), θ̇ = 2ω₀/cosh u, u = u₀ + ω₀t;
!>   rotation (θ̇ > 0): θ/2 = am(ku, 1/k), θ̇ = 2kω₀ dn(ku, 1/k); θ gains 2π in 2K(1/k)/(kω₀).
!> One phase function covers all three on the rising branch (θ̇ > 0, |θ| ≤ π):
!>   P(θ) = ω₀·(time from 0 to θ) = s R_F(y², k²c², k²)
!>        [= F(arcsin(s/k), k) for k < 1, = F(θ/2, 1/k)/k for k > 1, = artanh s for k = 1],
!> with y² = k² − s² taken from the velocity directly (no cancellation at the wall).
!> Libration start: u₀ = P(θ₀) if θ̇₀ ≥ 0, else 2K − P(θ₀) (sn(2K − u) = sn u, cn(2K − u) = −cn u).
!> Walls: the motion is wall-to-wall free flight. From a state moving towards +θ_w (mirror
!> θ → −θ otherwise), the first impact is at τ₁ = (P(θ_w) − P(θ₀))/ω₀, then every
!> T_c = 2P(θ_w)/ω₀ (the crossing time; P is odd); after n impacts the state is (−1)ⁿ times the
!> free flight that leaves −θ_w upwards, evaluated t − τₙ later. Backward time: the state at
!> −t from (θ₀, θ̇₀) is (θ, −θ̇) of the state at t from (θ₀, −θ̇₀).
!>
!> Numerics (own code, quad precision). K(k) = π/(2 AGM(1, k')) with k'² = c² − y² formed as a
!> product of differences; am(u, k) by the descending Landen (Gauss) transformation
!> (φ_N = 2ᴺa_N u, φ_{n−1} = ½(φ_n + arcsin((c_n/a_n) sin φ_n))) after reducing u by the period;
!> dn = sqrt((1 − k sn)(1 + k sn)); Carlson's R_F by duplication until the relative spread of
!> the arguments is below 1e-6, then the series of DLMF 19.36.1 through degree 3 in E₂, E₃
!> (truncation ~r⁸ < 1e-40).
!>
!> Accuracy, measured by the two cross-checks (`ctest --preset default -R ref_walls -V` prints
!> the numbers). (a) test/core/test_ref_walls_ode.pf: an independent order-30 Taylor-series
!> integrator in quad precision, impacts located on its step polynomials, 10 s horizons with
!> 16 to 39 impacts (walls 0.5, 0.7, 1.0; libration and rotation energies; backward; start on a
!> wall; separatrix), free libration and rotation: θ, θ̇ and impact times agree to 6e-33 ..
!> 1.2e-30 (3e-29 for a libration with k' = 0.018, where the period's sensitivity to energy
!> amplifies rounding); asserted 1e-26. (b) test/core/test_ref_walls_props.pf: period 4K/ω₀
!> against K from an independent trapezoidal quadrature to <= 4e-33 (rotation: 1e-33); K(1/√2)
!> against Γ(1/4)²/(4√π) to rounding; wall-to-wall period against Gauss–Legendre quadrature of
!> ∫dθ/θ̇ to 2e-34; energy along the solution (t in [−20, 20]) constant to 7e-32; |θ| = θ_w at
!> every impact; time reversal and the flow property (asserted 1e-28). The double results are
!> these rounded once: within half an ulp plus ~1e-29.
module vci_ref_pendulum_walls
  use iso_fortran_env, only: real64, real128
  implicit none
  private

  integer, parameter :: dp = real64
  !> Kind of the quad-precision interface (IEEE binary128).
  integer, parameter, public :: pendulum_walls_qp = real128
  integer, parameter :: qp = pendulum_walls_qp

  public :: pendulum_walls_params
  public :: pendulum_walls_exact, pendulum_walls_exact_qp
  public :: pendulum_walls_energy, pendulum_walls_energy_qp
  public :: pendulum_walls_period, pendulum_walls_period_qp

  !> Status values (stat argument).
  integer, parameter, public :: pendulum_walls_ok = 0
  !> Non-finite or non-positive parameter, non-finite input, start outside the walls, or a
  !> horizon with more than huge(0)/2 impacts. Outputs are zero.
  integer, parameter, public :: pendulum_walls_bad_input = 1
  !> More impacts than pendulum_walls_max_listed: state and n_impacts are right, impact_times
  !> holds only the first pendulum_walls_max_listed.
  integer, parameter, public :: pendulum_walls_too_many_impacts = 2
  !> impact_times could not be allocated; state and n_impacts are right.
  integer, parameter, public :: pendulum_walls_alloc_failed = 3
  integer, parameter, public :: pendulum_walls_max_listed = 10000000

  !> Scene parameters. theta_w >= π (default huge) means no walls.
  type :: pendulum_walls_params
    real(dp) :: g = 9.8_dp                  !< gravitational acceleration
    real(dp) :: ell = 1.0_dp                !< length
    real(dp) :: theta_w = huge(1.0_dp)      !< wall angle, walls at ±theta_w (0 < theta_w)
    real(dp) :: m = 1.0_dp                  !< mass (enters the energy only)
  end type pendulum_walls_params

  real(qp), parameter :: pi_q = 3.14159265358979323846264338327950288419716939937510582_qp
  real(qp), parameter :: eps_q = epsilon(1.0_qp)

  integer, parameter :: regime_rest = 0, regime_libration = 1, regime_separatrix = 2, &
                        regime_rotation = 3

  !> One free orbit: the invariant, the modulus in use and its quarter period.
  type :: orbit_t
    integer :: regime = regime_rest
    real(qp) :: w0 = 0      !< ω₀
    real(qp) :: k2 = 0      !< k² = y² + s²
    real(qp) :: k = 0       !< k
    real(qp) :: modulus = 0 !< k (libration) or 1/k (rotation)
    real(qp) :: comod = 0   !< complementary modulus of `modulus`
    real(qp) :: big_k = 0   !< K(modulus)
  end type orbit_t

contains

  !> Energy ½mℓ²θ̇² − mgℓ cosθ.
  pure real(dp) function pendulum_walls_energy(params, theta, omega) result(e)
    type(pendulum_walls_params), intent(in) :: params
    real(dp), intent(in) :: theta, omega
    e = 0.5_dp*params%m*params%ell**2*omega**2 - params%m*params%g*params%ell*cos(theta)
  end function pendulum_walls_energy

  !> Energy in quad precision (parameters taken as exact doubles).
  pure real(qp) function pendulum_walls_energy_qp(params, theta, omega) result(e)
    type(pendulum_walls_params), intent(in) :: params
    real(qp), intent(in) :: theta, omega
    real(qp) :: m, g, ell
    m = real(params%m, qp)
    g = real(params%g, qp)
    ell = real(params%ell, qp)
    e = 0.5_qp*m*ell**2*omega**2 - m*g*ell*cos(theta)
  end function pendulum_walls_energy_qp

  !> Period of the motion from (theta0, omega0), as a double: free libration 4K(k)/ω₀; rotation
  !> the time in which θ gains 2π, 2K(1/k)/(kω₀); at rest 2π/ω₀ (the small-amplitude limit);
  !> separatrix huge(1.0_dp); between walls with impacts 2T_c (two crossings). Bad input: −1.
  real(dp) function pendulum_walls_period(params, theta0, omega0) result(period)
    type(pendulum_walls_params), intent(in) :: params
    real(dp), intent(in) :: theta0, omega0
    real(qp) :: p
    p = pendulum_walls_period_qp(params, real(theta0, qp), real(omega0, qp))
    if (p > real(huge(1.0_dp), qp)) then
      period = huge(1.0_dp)
    else
      period = real(p, dp)
    end if
  end function pendulum_walls_period

  !> Quad-precision version of pendulum_walls_period (separatrix: huge(1.0_qp)).
  real(qp) function pendulum_walls_period_qp(params, theta0, omega0) result(period)
    type(pendulum_walls_params), intent(in) :: params
    real(qp), intent(in) :: theta0, omega0
    type(orbit_t) :: orb
    real(qp) :: sw
    character(len=80) :: msg

    period = -1
    if (.not. params_ok(params, msg)) return
    if (.not. (abs(theta0) <= huge(1.0_qp) .and. abs(omega0) <= huge(1.0_qp))) return
    orb = make_orbit(params, theta0, omega0)
    if (has_walls(params)) then
      if (abs(theta0) > real(params%theta_w, qp)) return
      sw = sin(real(params%theta_w, qp)/2)
      if (orb%k2 > sw**2) then
        period = 4*phase(orb, sw, cos(real(params%theta_w, qp)/2), orb%k2 - sw**2)/orb%w0
        return
      end if
    end if
    select case (orb%regime)
    case (regime_rest)
      period = 2*pi_q/orb%w0
    case (regime_libration)
      period = 4*orb%big_k/orb%w0
    case (regime_separatrix)
      period = huge(1.0_qp)
    case default
      period = 2*orb%big_k/(orb%k*orb%w0)
    end select
  end function pendulum_walls_period_qp

  !> State at time t (any sign) from θ(0) = theta0, θ̇(0) = omega0, and the impacts met on the
  !> way: n_impacts of them, at impact_times (in the order met: increasing in (0, t] for t > 0,
  !> decreasing in [t, 0) for t < 0). At an impact time the state returned is the one after the
  !> impact. A start on a wall moving outwards bounces at t = 0 (not listed); a motion that just
  !> reaches a wall with zero speed (k = sin(θ_w/2) exactly) has no impact. Without walls θ is
  !> continuous in t (rotations keep counting turns). The computation is in quad precision; the
  !> results are rounded once. impact_times is allocated (size n_impacts, at most
  !> pendulum_walls_max_listed) only when present. stat gets a pendulum_walls_* value and
  !> message (when present) a sentence naming the cause; without stat a failure is silent
  !> (outputs zero).
  subroutine pendulum_walls_exact(params, theta0, omega0, t, theta, omega, n_impacts, &
                                  impact_times, stat, message)
    type(pendulum_walls_params), intent(in) :: params
    real(dp), intent(in) :: theta0, omega0, t
    real(dp), intent(out) :: theta, omega
    integer, intent(out) :: n_impacts
    real(dp), allocatable, intent(out), optional :: impact_times(:)
    integer, intent(out), optional :: stat
    character(len=*), intent(out), optional :: message
    real(qp) :: th, om
    real(qp), allocatable :: times_q(:)
    integer :: info, ierr

    if (present(impact_times)) then
      call pendulum_walls_exact_qp(params, real(theta0, qp), real(omega0, qp), real(t, qp), &
                                   th, om, n_impacts, times_q, info, message)
      if (allocated(times_q)) then
        allocate (impact_times(size(times_q)), stat=ierr)
        if (ierr == 0) then
          impact_times = real(times_q, dp)
        else if (info == pendulum_walls_ok) then
          info = pendulum_walls_alloc_failed
          if (present(message)) message = 'pendulum_walls_exact: cannot allocate impact_times'
        end if
      end if
    else
      call pendulum_walls_exact_qp(params, real(theta0, qp), real(omega0, qp), real(t, qp), &
                                   th, om, n_impacts, stat=info, message=message)
    end if
    theta = real(th, dp)
    omega = real(om, dp)
    if (present(stat)) stat = info
  end subroutine pendulum_walls_exact

  !> Quad-precision version of pendulum_walls_exact: same meaning, real(pendulum_walls_qp)
  !> state, time and impact times (the parameters are the double ones taken as exact).
  subroutine pendulum_walls_exact_qp(params, theta0, omega0, t, theta, omega, n_impacts, &
                                     impact_times, stat, message)
    type(pendulum_walls_params), intent(in) :: params
    real(qp), intent(in) :: theta0, omega0, t
    real(qp), intent(out) :: theta, omega
    integer, intent(out) :: n_impacts
    real(qp), allocatable, intent(out), optional :: impact_times(:)
    integer, intent(out), optional :: stat
    character(len=*), intent(out), optional :: message
    type(orbit_t) :: orb
    real(qp) :: th0, om0, tt, sign_t, sign_x, tw, sw, cw, pw, tau1, tc, delta, u, nq
    integer :: info, n, n_list, j, ierr
    character(len=160) :: msg

    theta = 0
    omega = 0
    n_impacts = 0
    info = pendulum_walls_ok
    msg = ''
    if (.not. params_ok(params, msg)) then
      info = pendulum_walls_bad_input
    else if (.not. (abs(theta0) <= huge(1.0_qp) .and. abs(omega0) <= huge(1.0_qp) &
                    .and. abs(t) <= huge(1.0_qp))) then
      info = pendulum_walls_bad_input
      msg = 'pendulum_walls_exact: non-finite theta0, omega0 or t'
    else if (has_walls(params) .and. abs(theta0) > real(params%theta_w, qp)) then
      info = pendulum_walls_bad_input
      msg = 'pendulum_walls_exact: theta0 outside the walls'
    end if
    if (info /= pendulum_walls_ok) then
      if (present(stat)) stat = info
      if (present(message)) message = msg
      if (present(impact_times)) allocate (impact_times(0), stat=ierr)
      return
    end if

    ! Backward time: reverse the velocity, run forward, reverse again.
    sign_t = merge(-1.0_qp, 1.0_qp, t < 0)
    tt = abs(t)
    th0 = theta0
    om0 = sign_t*omega0
    orb = make_orbit(params, th0, om0)

    tw = real(params%theta_w, qp)
    sw = 0
    if (has_walls(params)) sw = sin(tw/2)
    if (.not. has_walls(params) .or. orb%k2 <= sw**2) then
      call free_state(orb, th0, om0, tt, theta, omega)
      n_list = 0
    else
      ! Mirror so that the motion heads for +θ_w (omega0 /= 0 here since k² > sin²(θ_w/2)).
      sign_x = merge(-1.0_qp, 1.0_qp, om0 < 0)
      th0 = sign_x*th0
      om0 = sign_x*om0
      if (th0 >= tw) then
        ! On the wall moving out: the bounce at t = 0, seen as the mirror image.
        sign_x = -sign_x
        th0 = -tw
      end if
      cw = cos(tw/2)
      pw = phase(orb, sw, cw, orb%k2 - sw**2)
      tau1 = (pw - phase(orb, sin(th0/2), cos(th0/2), (om0/(2*orb%w0))**2))/orb%w0
      tc = 2*pw/orb%w0
      if (tt < tau1) then
        n = 0
        delta = tt
        call free_state(orb, th0, om0, delta, theta, omega)
      else
        nq = 1 + floor((tt - tau1)/tc)
        if (nq > real(huge(0)/2, qp)) then
          if (present(stat)) stat = pendulum_walls_bad_input
          if (present(message)) message = 'pendulum_walls_exact: more than huge(0)/2 impacts'
          if (present(impact_times)) allocate (impact_times(0), stat=ierr)
          return
        end if
        n = int(nq)
        delta = tt - (tau1 + (n - 1)*tc)
        ! Leaving −θ_w upwards (even n) or its mirror image, leaving +θ_w downwards (odd n).
        u = -pw + orb%w0*delta
        call flight(orb, u, theta, omega)
        if (mod(n, 2) == 1) then
          theta = -theta
          omega = -omega
        end if
      end if
      theta = sign_x*theta
      omega = sign_x*omega
      n_impacts = n
      n_list = min(n, pendulum_walls_max_listed)
      if (n > pendulum_walls_max_listed) then
        info = pendulum_walls_too_many_impacts
        msg = 'pendulum_walls_exact: more impacts than pendulum_walls_max_listed; list truncated'
      end if
    end if
    omega = sign_t*omega

    if (present(impact_times)) then
      allocate (impact_times(n_list), stat=ierr)
      if (ierr /= 0) then
        info = pendulum_walls_alloc_failed
        msg = 'pendulum_walls_exact: cannot allocate impact_times'
      else
        do j = 1, n_list
          impact_times(j) = sign_t*(tau1 + (j - 1)*tc)
        end do
      end if
    end if
    if (present(stat)) stat = info
    if (present(message)) message = msg
  end subroutine pendulum_walls_exact_qp

  logical function params_ok(params, msg)
    type(pendulum_walls_params), intent(in) :: params
    character(len=*), intent(inout) :: msg
    params_ok = params%g > 0 .and. params%g <= huge(1.0_dp) .and. params%ell > 0 &
                .and. params%ell <= huge(1.0_dp) .and. params%theta_w > 0 &
                .and. params%m > 0 .and. params%m <= huge(1.0_dp)
    if (.not. params_ok) msg = 'pendulum_walls_exact: g, ell, m must be positive and finite, '// &
                               'theta_w positive'
  end function params_ok

  pure logical function has_walls(params)
    type(pendulum_walls_params), intent(in) :: params
    has_walls = real(params%theta_w, qp) < pi_q
  end function has_walls

  !> The free orbit through (theta0, omega0): invariant, regime, modulus and K.
  function make_orbit(params, theta0, omega0) result(orb)
    type(pendulum_walls_params), intent(in) :: params
    real(qp), intent(in) :: theta0, omega0
    type(orbit_t) :: orb
    real(qp) :: y, c, kp2

    orb%w0 = sqrt(real(params%g, qp)/real(params%ell, qp))
    y = abs(omega0)/(2*orb%w0)
    c = abs(cos(theta0/2))
    orb%k2 = y**2 + sin(theta0/2)**2
    orb%k = sqrt(orb%k2)
    ! 1 − k² = c² − y², formed without cancelling the leading 1.
    kp2 = (c - y)*(c + y)
    if (orb%k2 == 0) then
      orb%regime = regime_rest
    else if (kp2 > 0) then
      orb%regime = regime_libration
      orb%modulus = orb%k
      orb%comod = sqrt(kp2)
      orb%big_k = ellip_k(orb%comod)
    else if (kp2 == 0) then
      orb%regime = regime_separatrix
    else
      orb%regime = regime_rotation
      orb%modulus = 1/orb%k
      orb%comod = sqrt(-kp2)/orb%k
      orb%big_k = ellip_k(orb%comod)
    end if
  end function make_orbit

  !> Phase P(θ) = s R_F(y², k²c², k²) on the rising branch, |θ| ≤ π (c ≥ 0), y² = k² − s².
  pure real(qp) function phase(orb, s, c, y2)
    type(orbit_t), intent(in) :: orb
    real(qp), intent(in) :: s, c, y2
    if (s == 0) then
      phase = 0
    else
      phase = s*carlson_rf(y2, orb%k2*c**2, orb%k2)
    end if
  end function phase

  !> Free motion for time t >= 0 from (theta0, omega0): the phase at t = 0, then flight.
  subroutine free_state(orb, theta0, omega0, t, theta, omega)
    type(orbit_t), intent(in) :: orb
    real(qp), intent(in) :: theta0, omega0, t
    real(qp), intent(out) :: theta, omega
    real(qp) :: sgn, th, thr, turns, u0

    if (orb%regime == regime_rest) then
      theta = theta0
      omega = 0
      return
    end if
    ! Rotation and separatrix run on the rising branch: mirror a falling start.
    sgn = 1
    th = theta0
    if (orb%regime /= regime_libration .and. omega0 < 0) then
      sgn = -1
      th = -theta0
    end if
    ! θ₀ = θᵣ + 2π·turns with |θᵣ| <= π, where the phase is defined.
    turns = anint(th/(2*pi_q))
    thr = th - 2*pi_q*turns
    u0 = phase(orb, sin(thr/2), cos(thr/2), (omega0/(2*orb%w0))**2)
    select case (orb%regime)
    case (regime_libration)
      if (omega0 < 0) u0 = 2*orb%big_k - u0
      call flight(orb, u0 + orb%w0*t, theta, omega)
      theta = theta + 2*pi_q*turns
    case (regime_separatrix)
      call flight(orb, u0 + orb%w0*t, theta, omega)
      theta = theta + 2*pi_q*turns
    case default
      ! am(v + 2K) = am(v) + π: each turn adds 2K(1/k) to v = k·u.
      call flight(orb, u0 + (2*orb%big_k*turns)/orb%k + orb%w0*t, theta, omega)
    end select
    theta = sgn*theta
    omega = sgn*omega
  end subroutine free_state

  !> State at phase u on the orbit (the rising branch through θ = 0 at u = 0).
  pure subroutine flight(orb, u, theta, omega)
    type(orbit_t), intent(in) :: orb
    real(qp), intent(in) :: u
    real(qp), intent(out) :: theta, omega
    real(qp) :: ur, phi, sn, v, j

    select case (orb%regime)
    case (regime_libration)
      ur = u - 4*orb%big_k*anint(u/(4*orb%big_k))
      phi = jacobi_am(ur, orb%modulus, orb%comod)
      sn = sin(phi)
      theta = 2*atan2(orb%k*sn, sqrt((1 - orb%k*sn)*(1 + orb%k*sn)))
      omega = 2*orb%w0*orb%k*cos(phi)
    case (regime_separatrix)
      theta = 2*atan(sinh(u))
      omega = 2*orb%w0/cosh(u)
    case (regime_rotation)
      v = orb%k*u
      j = anint(v/(2*orb%big_k))
      phi = jacobi_am(v - 2*orb%big_k*j, orb%modulus, orb%comod)
      sn = sin(phi)
      theta = 2*phi + 2*pi_q*j
      omega = 2*orb%w0*sqrt((orb%k - sn)*(orb%k + sn))
    case default
      theta = 0
      omega = 0
    end select
  end subroutine flight

  !> Complete K = π / (2 AGM(1, k')), from the complementary modulus.
  pure real(qp) function ellip_k(kp)
    real(qp), intent(in) :: kp
    real(qp) :: a, b, a_new
    integer :: it
    a = 1
    b = kp
    do it = 1, 60
      if (abs(a - b) <= eps_q*a) exit
      a_new = (a + b)/2
      b = sqrt(a*b)
      a = a_new
    end do
    ellip_k = pi_q/(a + b)
  end function ellip_k

  !> Amplitude am(u, k) by the descending Landen transformation (A&S 16.4): a₀ = 1, b₀ = k',
  !> c₀ = k, AGM steps until c_N is negligible, φ_N = 2ᴺa_N u, then back down.
  pure real(qp) function jacobi_am(u, k, kp) result(phi)
    real(qp), intent(in) :: u, k, kp
    integer, parameter :: max_steps = 60
    real(qp) :: a(0:max_steps), c(0:max_steps), b, a_new
    integer :: n, nn
    a(0) = 1
    b = kp
    c(0) = k
    nn = 0
    do n = 1, max_steps
      if (abs(c(n - 1)) <= eps_q*a(n - 1)) exit
      a_new = (a(n - 1) + b)/2
      c(n) = (a(n - 1) - b)/2
      b = sqrt(a(n - 1)*b)
      a(n) = a_new
      nn = n
    end do
    phi = 2.0_qp**nn*a(nn)*u
    do n = nn, 1, -1
      phi = (phi + asin(c(n)/a(n)*sin(phi)))/2
    end do
  end function jacobi_am

  !> Carlson's R_F(x, y, z) (x, y, z >= 0, at most one zero) by duplication, then the
  !> DLMF 19.36.1 series in E₂ = XY − Z², E₃ = XYZ with X = 1 − x/A etc.
  pure real(qp) function carlson_rf(x0, y0, z0) result(rf)
    real(qp), intent(in) :: x0, y0, z0
    real(qp) :: x, y, z, lam, a, dx, dy, dz, e2, e3
    integer :: it
    x = x0
    y = y0
    z = z0
    do it = 1, 200
      a = (x + y + z)/3
      dx = 1 - x/a
      dy = 1 - y/a
      dz = 1 - z/a
      if (max(abs(dx), abs(dy), abs(dz)) < 1.0e-6_qp) exit
      lam = sqrt(x)*sqrt(y) + sqrt(y)*sqrt(z) + sqrt(z)*sqrt(x)
      x = (x + lam)/4
      y = (y + lam)/4
      z = (z + lam)/4
    end do
    e2 = dx*dy - dz**2
    e3 = dx*dy*dz
    rf = (1 - e2/10 + e3/14 + e2**2/24 - 3*e2*e3/44 - 5*e2**3/208 + 3*e3**2/104 &
          + e2**2*e3/16)/sqrt(a)
  end function carlson_rf

end module vci_ref_pendulum_walls
