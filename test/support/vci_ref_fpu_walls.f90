!> Event-driven reference for an FPU-β chain between walls, in quad precision. Independent of the
!> vci library: only iso_fortran_env.
!>
!> Scene. n particles of unit mass with displacements x_1..x_n, fixed ends x_0 = x_{n+1} = 0,
!> nearest-neighbour springs V(r) = r²/2 + β r⁴/4 on the bond stretches r_j = x_{j+1} − x_j
!> (j = 0..n), so ẍ_i = r_i + β r_i³ − r_{i−1} − β r_{i−1}³ and
!> H = Σ v_i²/2 + Σ_j (r_j²/2 + β r_j⁴/4). Walls: every particle is confined to |x_i| ≤ w; when
!> particle i reaches ±w its velocity reverses, v_i → −v_i (the elastic impact on the constraint
!> |x_i| ≤ w with unit masses), the others are unchanged; H is conserved. w = huge: no walls.
!>
!> Method. The right-hand side is polynomial, so its Taylor coefficients follow from Cauchy
!> products (r², r³ by convolution): a Taylor-series method of order `order` (default 30) with
!> fixed step `step` (default 0.01), all in quad precision. Each step's polynomials are the
!> dense output: a particle whose polynomial bound Σ|X_k||h|ᵏ reaches w is sampled at 32
!> points; the first sign change of x_i ∓ w is polished by safeguarded Newton on the
!> polynomial; the earliest such root among all particles is the impact, the state is evaluated
!> there, that particle is put exactly on its wall with v_i reversed, and the fixed grid
!> restarts from the impact. A particle on a wall moving out is reflected at once (the second
!> of two simultaneous impacts). A graze that leaves and re-enters the admissible set between
!> two samples is not seen (its depth would be below ~(h/32)²|ẍ|/8). Backward time: velocities
!> reversed, integrated forward, reversed again.
!>
!> Cost per step grows as order²·n (the cubic's convolutions); n = 256 works, only slowly.
!>
!> Accuracy (test/core/test_ref_fpu_walls.pf; `ctest --preset default -R ref_fpu -V` prints
!> the numbers): β = 0 without walls against the exact normal modes, 3e-34 (n = 4) and 2e-33
!> (n = 32) at t = 2.3; one particle between walls against its closed-form impact times and
!> state, 9e-33 over 16 impacts; the β = 1 chain with walls, steps 0.01 and 0.005: n = 4,
!> w = 0.5, 10 s, 31 impacts: same impact sequence, times within 2e-32, state within 6e-32,
!> energy (2.67) conserved to 4e-34, reversal back to the start within 2e-32; n = 32, w = 0.6,
!> 2 s, 41 impacts: 3e-33, 7e-33, 3e-33 of 17.2, 6e-33.
module vci_ref_fpu_walls
  use iso_fortran_env, only: real64, real128
  implicit none
  private

  integer, parameter :: dp = real64
  !> Kind of the quad-precision interface (IEEE binary128).
  integer, parameter, public :: fpu_walls_qp = real128
  integer, parameter :: qp = fpu_walls_qp

  public :: fpu_walls_params, fpu_walls_run, fpu_walls_run_qp
  public :: fpu_walls_energy, fpu_walls_energy_qp

  !> Status values (stat argument).
  integer, parameter, public :: fpu_walls_ok = 0
  !> Empty chain, non-finite input, start outside the walls, w <= 0, step <= 0, order < 2.
  integer, parameter, public :: fpu_walls_bad_input = 1
  !> More than max_impacts impacts: the outputs hold the state at the last one reached.
  integer, parameter, public :: fpu_walls_too_many_impacts = 2
  !> An impact could not be located (Newton/bisection did not settle), or a step's polynomial
  !> became non-finite (step far too long for the motion).
  integer, parameter, public :: fpu_walls_event_failed = 3
  integer, parameter, public :: fpu_walls_alloc_failed = 4

  !> Scene and integrator parameters.
  type :: fpu_walls_params
    real(dp) :: beta = 1.0_dp            !< quartic coefficient of the springs
    real(dp) :: w = huge(1.0_dp)         !< walls at ±w for every particle (huge: none)
    real(dp) :: step = 0.01_dp           !< fixed Taylor step (time units)
    integer :: order = 30                !< Taylor order
    integer :: max_impacts = 1000000     !< cap on the number of impacts
  end type fpu_walls_params

  integer, parameter :: n_samples = 32

contains

  !> H = Σ v²/2 + Σ (r²/2 + β r⁴/4), r_j = x_{j+1} − x_j with x_0 = x_{n+1} = 0.
  pure real(dp) function fpu_walls_energy(params, x, v) result(e)
    type(fpu_walls_params), intent(in) :: params
    real(dp), intent(in) :: x(:), v(:)
    e = real(fpu_walls_energy_qp(params, real(x, qp), real(v, qp)), dp)
  end function fpu_walls_energy

  !> Energy in quad precision (β taken as the exact double).
  pure real(qp) function fpu_walls_energy_qp(params, x, v) result(e)
    type(fpu_walls_params), intent(in) :: params
    real(qp), intent(in) :: x(:), v(:)
    real(qp) :: r(0:size(x)), beta
    integer :: n
    n = size(x)
    beta = real(params%beta, qp)
    r(0) = x(1)
    r(1:n - 1) = x(2:n) - x(1:n - 1)
    r(n) = -x(n)
    e = sum(v**2)/2 + sum(r**2/2 + beta*r**4/4)
  end function fpu_walls_energy_qp

  !> State at time t (any sign) from (x0, v0), size n each, and the impacts met on the way, in
  !> the order met: n_impacts of them, at impact_times (decreasing for t < 0) by particle
  !> impact_particles (1..n); both allocated when present. At an impact time the state is the
  !> one after it. On a nonzero stat the outputs hold the state reached so far and message
  !> (when present) names the cause and the time.
  subroutine fpu_walls_run(params, x0, v0, t, x, v, n_impacts, impact_times, impact_particles, &
                           stat, message)
    type(fpu_walls_params), intent(in) :: params
    real(dp), intent(in) :: x0(:), v0(:), t
    real(dp), intent(out) :: x(:), v(:)
    integer, intent(out) :: n_impacts
    real(dp), allocatable, intent(out), optional :: impact_times(:)
    integer, allocatable, intent(out), optional :: impact_particles(:)
    integer, intent(out), optional :: stat
    character(len=*), intent(out), optional :: message
    real(qp) :: xq(size(x0)), vq(size(x0))
    real(qp), allocatable :: times_q(:)
    integer :: info, ierr

    call fpu_walls_run_qp(params, real(x0, qp), real(v0, qp), real(t, qp), xq, vq, n_impacts, &
                          times_q, impact_particles, info, message)
    x = real(xq, dp)
    v = real(vq, dp)
    if (present(impact_times)) then
      allocate (impact_times(size(times_q)), stat=ierr)
      if (ierr == 0) then
        impact_times = real(times_q, dp)
      else if (info == fpu_walls_ok) then
        info = fpu_walls_alloc_failed
        if (present(message)) message = 'fpu_walls_run: cannot allocate impact_times'
      end if
    end if
    if (present(stat)) stat = info
  end subroutine fpu_walls_run

  !> Quad-precision version of fpu_walls_run (same meaning; x and v of size n; the impact
  !> times always allocated).
  subroutine fpu_walls_run_qp(params, x0, v0, t, x, v, n_impacts, impact_times, &
                              impact_particles, stat, message)
    type(fpu_walls_params), intent(in) :: params
    real(qp), intent(in) :: x0(:), v0(:), t
    real(qp), intent(out) :: x(:), v(:)
    integer, intent(out) :: n_impacts
    real(qp), allocatable, intent(out) :: impact_times(:)
    integer, allocatable, intent(out), optional :: impact_particles(:)
    integer, intent(out), optional :: stat
    character(len=*), intent(out), optional :: message
    real(qp), allocatable :: cx(:, :), cv(:, :), times(:)
    integer, allocatable :: who(:)
    real(qp) :: w, beta, h, tt, now, sign_t, tau, hs
    integer :: n, nord, info, ierr, i, hit
    character(len=160) :: msg

    n = size(x0)
    nord = params%order
    x = 0
    v = 0
    n_impacts = 0
    info = fpu_walls_ok
    msg = ''
    w = real(params%w, qp)
    beta = real(params%beta, qp)
    h = real(params%step, qp)
    if (n < 1 .or. size(v0) /= n .or. size(x) /= n .or. size(v) /= n) then
      info = fpu_walls_bad_input
      msg = 'fpu_walls_run: x0, v0, x, v must have the same size n >= 1'
    else if (.not. (params%w > 0 .and. params%step > 0 .and. params%step <= huge(1.0_dp) &
                    .and. abs(params%beta) <= huge(1.0_dp) .and. nord >= 2)) then
      info = fpu_walls_bad_input
      msg = 'fpu_walls_run: need w > 0, finite step > 0, finite beta, order >= 2'
    else if (.not. (all(abs(x0) <= huge(1.0_qp)) .and. all(abs(v0) <= huge(1.0_qp)) &
                    .and. abs(t) <= huge(1.0_qp))) then
      info = fpu_walls_bad_input
      msg = 'fpu_walls_run: non-finite x0, v0 or t'
    else if (any(abs(x0) > w)) then
      info = fpu_walls_bad_input
      msg = 'fpu_walls_run: x0 outside the walls'
    end if
    allocate (cx(0:nord, 0:n + 1), cv(0:nord, n), times(64), who(64), stat=ierr)
    if (ierr /= 0 .and. info == fpu_walls_ok) then
      info = fpu_walls_alloc_failed
      msg = 'fpu_walls_run: cannot allocate work arrays'
    end if
    if (info /= fpu_walls_ok) then
      allocate (impact_times(0), stat=ierr)
      if (present(impact_particles)) allocate (impact_particles(0), stat=ierr)
      if (present(stat)) stat = info
      if (present(message)) message = msg
      return
    end if

    sign_t = merge(-1.0_qp, 1.0_qp, t < 0)
    tt = abs(t)
    x = x0
    v = sign_t*v0
    now = 0
    do
      ! On a wall moving out: reflect now (start on a wall, or a simultaneous impact).
      do i = 1, n
        if (abs(x(i)) >= w .and. x(i)*v(i) > 0) then
          if (now > 0) call record(i)
          if (info /= fpu_walls_ok) exit
          x(i) = sign(w, x(i))
          v(i) = -v(i)
        end if
      end do
      if (info /= fpu_walls_ok .or. now >= tt) exit
      hs = min(h, tt - now)
      call taylor_coefficients(beta, x, v, cx, cv)
      call first_impact(cx, w, hs, tau, hit, info)
      if (info /= fpu_walls_ok) then
        write (msg, '(a, es12.5)') 'fpu_walls_run: impact not located or step diverged at t =', &
          real(sign_t*now, dp)
        exit
      end if
      ! Rounding may put a particle a hair beyond its wall: back onto it.
      if (hit == 0) then
        call evaluate(cx, cv, hs, x, v)
        x = max(-w, min(w, x))
        now = merge(tt, now + hs, hs == tt - now)
      else
        call evaluate(cx, cv, tau, x, v)
        x = max(-w, min(w, x))
        now = now + tau
        call record(hit)
        if (info /= fpu_walls_ok) exit
        x(hit) = sign(w, x(hit))
        v(hit) = -v(hit)
      end if
    end do

    v = sign_t*v
    allocate (impact_times(n_impacts), stat=ierr)
    if (ierr == 0) impact_times = times(:n_impacts)
    if (present(impact_particles)) then
      allocate (impact_particles(n_impacts), stat=ierr)
      if (ierr == 0) impact_particles = who(:n_impacts)
    end if
    if (ierr /= 0 .and. info == fpu_walls_ok) then
      info = fpu_walls_alloc_failed
      msg = 'fpu_walls_run: cannot allocate the impact lists'
    end if
    if (present(stat)) stat = info
    if (present(message)) message = msg

  contains

    subroutine record(particle)
      integer, intent(in) :: particle
      real(qp), allocatable :: t_new(:)
      integer, allocatable :: w_new(:)
      if (n_impacts >= params%max_impacts) then
        info = fpu_walls_too_many_impacts
        write (msg, '(a, es12.5)') 'fpu_walls_run: more than max_impacts impacts by t =', &
          real(sign_t*now, dp)
        return
      end if
      if (n_impacts == size(times)) then
        allocate (t_new(2*size(times)), w_new(2*size(times)), stat=ierr)
        if (ierr /= 0) then
          info = fpu_walls_alloc_failed
          msg = 'fpu_walls_run: cannot grow the impact lists'
          return
        end if
        t_new(:n_impacts) = times
        w_new(:n_impacts) = who
        call move_alloc(t_new, times)
        call move_alloc(w_new, who)
      end if
      n_impacts = n_impacts + 1
      times(n_impacts) = sign_t*now
      who(n_impacts) = particle
    end subroutine record

  end subroutine fpu_walls_run_qp

  !> Normalized Taylor coefficients X_k, V_k (x(τ) = Σ X_k τᵏ) about (x, v) for the chain:
  !> X_{k+1} = V_k/(k+1), V_{k+1} = F_k/(k+1), F_k from the bond coefficients r_k and the
  !> Cauchy products (r²)_k, (r³)_k. cx(:, 0) and cx(:, n+1) are the fixed ends (zero).
  pure subroutine taylor_coefficients(beta, x, v, cx, cv)
    real(qp), intent(in) :: beta, x(:), v(:)
    real(qp), intent(out) :: cx(0:, 0:), cv(0:, :)
    real(qp) :: r(0:ubound(cx, 1), 0:size(x)), r2(0:ubound(cx, 1), 0:size(x))
    real(qp) :: r3(0:size(x)), f
    integer :: n, nord, k, m, j, i
    n = size(x)
    nord = ubound(cx, 1)
    cx = 0
    cx(0, 1:n) = x
    cv(0, :) = v
    do k = 0, nord - 1
      do j = 0, n
        r(k, j) = cx(k, j + 1) - cx(k, j)
        ! (r²)_k = Σ_m r_m r_{k−m}, each pair once.
        r2(k, j) = 0
        do m = 0, (k + 1)/2 - 1
          r2(k, j) = r2(k, j) + r(m, j)*r(k - m, j)
        end do
        r2(k, j) = 2*r2(k, j)
        if (mod(k, 2) == 0) r2(k, j) = r2(k, j) + r(k/2, j)**2
        r3(j) = 0
        do m = 0, k
          r3(j) = r3(j) + r2(m, j)*r(k - m, j)
        end do
      end do
      do i = 1, n
        f = r(k, i) - r(k, i - 1) + beta*(r3(i) - r3(i - 1))
        cx(k + 1, i) = cv(k, i)/(k + 1)
        cv(k + 1, i) = f/(k + 1)
      end do
    end do
  end subroutine taylor_coefficients

  pure real(qp) function horner(p, s)
    real(qp), intent(in) :: p(0:), s
    integer :: k
    horner = p(ubound(p, 1))
    do k = ubound(p, 1) - 1, 0, -1
      horner = horner*s + p(k)
    end do
  end function horner

  pure real(qp) function dhorner(p, s)
    real(qp), intent(in) :: p(0:), s
    integer :: k
    dhorner = ubound(p, 1)*p(ubound(p, 1))
    do k = ubound(p, 1) - 1, 1, -1
      dhorner = dhorner*s + k*p(k)
    end do
  end function dhorner

  pure subroutine evaluate(cx, cv, s, x, v)
    real(qp), intent(in) :: cx(0:, 0:), cv(0:, :), s
    real(qp), intent(inout) :: x(:), v(:)
    integer :: i
    do i = 1, size(x)
      x(i) = horner(cx(:, i), s)
      v(i) = horner(cv(:, i), s)
    end do
  end subroutine evaluate

  !> Earliest τ in (0, hs] at which a particle's polynomial reaches ±w (hit = 0: none).
  pure subroutine first_impact(cx, w, hs, tau, hit, info)
    real(qp), intent(in) :: cx(0:, 0:), w, hs
    real(qp), intent(out) :: tau
    integer, intent(out) :: hit
    integer, intent(inout) :: info
    real(qp) :: bound, s_lo, s_hi, p_hi, root, pk
    integer :: i, j, k

    hit = 0
    tau = huge(1.0_qp)
    do i = 1, ubound(cx, 2) - 1
      bound = 0
      pk = 1
      do k = 0, ubound(cx, 1)
        bound = bound + abs(cx(k, i))*pk
        pk = pk*hs
      end do
      if (.not. (bound <= huge(1.0_qp))) then
        info = fpu_walls_event_failed
        return
      end if
      if (bound < w) cycle
      ! Candidate: the first sample beyond a wall, then the root between it and the one before.
      s_lo = 0
      do j = 1, n_samples
        if (s_lo >= tau) exit
        s_hi = hs*j/n_samples
        p_hi = horner(cx(:, i), s_hi)
        if (abs(p_hi) > w) then
          call polish(cx(:, i), sign(w, p_hi), s_lo, s_hi, root, info)
          if (info /= fpu_walls_ok) return
          if (root < tau) then
            tau = root
            hit = i
          end if
          exit
        end if
        s_lo = s_hi
      end do
    end do
    if (hit == 0) tau = hs
  end subroutine first_impact

  !> Root of p(s) = target in [lo, hi] (p(lo) inside, p(hi) beyond): Newton, kept in the
  !> bracket by bisection, until the Newton step is at rounding level or the bracket closes.
  pure subroutine polish(p, target, lo_in, hi_in, root, info)
    real(qp), intent(in) :: p(0:), target, lo_in, hi_in
    real(qp), intent(out) :: root
    integer, intent(inout) :: info
    real(qp) :: lo, hi, f, f_lo, step
    integer :: it
    lo = lo_in
    hi = hi_in
    f_lo = horner(p, lo) - target
    root = lo + (hi - lo)*f_lo/(f_lo - (horner(p, hi) - target))
    do it = 1, 200
      f = horner(p, root) - target
      if (f == 0) exit
      if (sign(1.0_qp, f) == sign(1.0_qp, f_lo)) then
        lo = root
      else
        hi = root
      end if
      step = -f/dhorner(p, root)
      if (abs(step) <= 4*epsilon(1.0_qp)*hi_in) then
        root = root + step
        exit
      end if
      if (.not. (root + step > lo .and. root + step < hi)) step = (lo + hi)/2 - root
      root = root + step
      if (hi - lo <= 4*spacing(hi)) exit
    end do
    if (it > 200) info = fpu_walls_event_failed
  end subroutine polish

end module vci_ref_fpu_walls
