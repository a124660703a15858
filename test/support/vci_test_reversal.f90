!> Random scenes for the reversal property (issue 24, item 1; docs/BACKWARD.md): a particle in a
!> box [0, w] x [0, ht] with a Lagrangian quartic in the velocity, a magnetic term, gravity and a
!> spring, so that E_d depends on the step length and several impacts fall in one step:
!>   L(q, v) = |v|²/2 + c |v|⁴/4 + b/2 (x v_y - y v_x) - g y - k/2 |q - qc|².
!> `reversal_lag_t` is L for the library's schemes; `reversal_ld_t` the same L with the midpoint L_d
!> written by hand (a user's symmetric L_d). `round_trip` runs N steps forward and N back (m = 0:
!> the (-) step inverts the (+) step, impacts included) and reports how far the start moved.
module vci_test_reversal
  use vci
  implicit none
  private

  !> The scene's parameters (shared by both model kinds).
  type, public :: reversal_scene_t
    real(dp) :: c = 0.0_dp, b = 0.0_dp, grav = 0.0_dp, k = 0.0_dp, qc(2) = 0.0_dp
    real(dp) :: width = 1.0_dp, height = 1.0_dp
    real(dp) :: q0(2) = 0.5_dp, v0(2) = 0.0_dp, h = 0.1_dp
    integer :: nsteps = 100
    integer :: scheme = VCI_SCHEME_MIDPOINT, stages = 0   !< VCI_SCHEME_DISCRETE: reversal_ld_t
  end type reversal_scene_t

  type, extends(vci_lagrangian_t), public :: reversal_lag_t
    type(reversal_scene_t) :: s
  contains
    procedure :: lagrangian => rl_lagrangian, dl_dq => rl_dl_dq, dl_dv => rl_dl_dv, hessians => rl_hessians
    procedure :: gaps => box_gaps, gap_gradients => box_gap_grads, energy => rl_energy
  end type reversal_lag_t

  type, extends(vci_model_t), public :: reversal_ld_t
    type(reversal_scene_t) :: s
  contains
    procedure :: d1 => ld_d1, d2 => ld_d2, d3 => ld_d3
    procedure :: gaps => ld_gaps, gap_gradients => ld_gap_grads, energy => ld_energy
  end type reversal_ld_t

  !> What a round trip measured.
  type, public :: reversal_result_t
    integer :: stat = VCI_OK
    character(len=300) :: message = ''
    real(dp) :: err_q = huge(1.0_dp), err_p = huge(1.0_dp)   !< relative distance to the start
    integer :: impacts_fwd = 0, impacts_bwd = 0
    integer :: multi_steps = 0           !< forward steps with two or more impacts
    integer :: fallbacks_fwd = 0, fallbacks_bwd = 0
    integer :: touches = 0               !< impacts with no impulse (tangential touches), both directions
    integer :: irreversible = 0          !< impacts that could not be tied (irreversible_impacts), both directions
  end type reversal_result_t

  public :: random_scene, round_trip, scene_label, forward_growth, print_forward_impacts

contains

  ! ---- the scene ----

  !> A scene drawn from seed (xorshift64*, so that the Fortran test and any other driver agree):
  !> one of left, midpoint, lobatto s = 2, 3 or the hand-written midpoint L_d; a box from 0.15 to 1
  !> wide, speeds of 2 to 6 and steps of 0.02 to 0.25 (several walls within a step), forces that
  !> move E_d with the step length.
  !> firm: impacts well away from a graze (speeds 3 to 6 against weaker forces, at most 40 steps, so
  !> that the box's chaos amplifies solver round-off by less than 1e3); else the wide family below
  !> (soft impacts included, where the issue's fallback and root choice are not yet reversible).
  function random_scene(seed, firm) result(s)
    integer, intent(in) :: seed
    logical, intent(in) :: firm
    type(reversal_scene_t) :: s
    integer(i8) :: state
    real(dp) :: speed, angle
    integer :: kind
    state = int(seed, i8) * 2654435761_i8 + 88172645463325252_i8
    kind = int(draw(state) * 5.0_dp)
    select case (kind)
    case (0); s%scheme = VCI_SCHEME_LEFT
    case (1); s%scheme = VCI_SCHEME_MIDPOINT
    case (2); s%scheme = VCI_SCHEME_LOBATTO; s%stages = 2
    case (3); s%scheme = VCI_SCHEME_LOBATTO; s%stages = 3
    case default; s%scheme = VCI_SCHEME_DISCRETE
    end select
    s%c = 2.0_dp * draw(state)
    s%b = 6.0_dp * draw(state) - 3.0_dp
    s%grav = 10.0_dp * draw(state)
    s%k = 20.0_dp * draw(state)
    s%width = 0.15_dp + 0.85_dp * draw(state)
    s%height = 0.15_dp + 0.85_dp * draw(state)
    s%qc = [s%width * draw(state), s%height * draw(state)]
    s%q0 = [s%width * (0.2_dp + 0.6_dp * draw(state)), s%height * (0.2_dp + 0.6_dp * draw(state))]
    speed = 2.0_dp + 4.0_dp * draw(state)
    angle = 6.283185307179586_dp * draw(state)
    s%h = 0.02_dp + 0.23_dp * draw(state)
    s%nsteps = 40 + int(60.0_dp * draw(state))
    if (firm) then
      s%c = 0.25_dp * s%c; s%b = 0.5_dp * s%b; s%grav = 0.3_dp * s%grav; s%k = 0.25_dp * s%k
      speed = 3.0_dp + 0.75_dp * (speed - 2.0_dp)
      s%nsteps = s%nsteps / 2
    end if
    ! the initial pair (q0, q0 + h v0) lies in the box: the speed is cut where it would not
    s%v0 = [cos(angle), sin(angle)]
    s%v0 = min(speed, 0.9_dp * reach(s%q0, s%v0, s%width, s%height) / s%h) * s%v0
  end function random_scene

  !> How far from q along the unit vector d the box [0, w] x [0, ht] extends.
  real(dp) function reach(q, d, w, ht)
    real(dp), intent(in) :: q(2), d(2), w, ht
    reach = huge(1.0_dp)
    if (d(1) > 0.0_dp) reach = min(reach, (w - q(1)) / d(1))
    if (d(1) < 0.0_dp) reach = min(reach, -q(1) / d(1))
    if (d(2) > 0.0_dp) reach = min(reach, (ht - q(2)) / d(2))
    if (d(2) < 0.0_dp) reach = min(reach, -q(2) / d(2))
  end function reach

  !> Uniform in [0, 1) (xorshift64*; the state is never 0).
  real(dp) function draw(state)
    integer(i8), intent(inout) :: state
    integer, parameter :: i16 = selected_int_kind(38)
    integer(i16), parameter :: mult = 2685821657736338717_i16, two64 = 2_i16**64
    state = ieor(state, shiftr(state, 12))
    state = ieor(state, shiftl(state, 25))
    state = ieor(state, shiftr(state, 27))
    ! the product modulo 2^64 in 128-bit integers: a wrapping 64-bit multiply is signed overflow,
    ! undefined in Fortran (UBSan stops on it); the top 53 of the low 64 bits, as before
    draw = real(modulo(int(state, i16) * mult, two64) / 2048_i16, dp) / 9007199254740992.0_dp
  end function draw

  function scene_label(s) result(label)
    type(reversal_scene_t), intent(in) :: s
    character(len=200) :: label
    write (label, '(a,i0,a,i0,4(a,f6.3),a,2f6.3,a,f6.3,a,i0)') 'scheme ', s%scheme, ' s ', s%stages, &
      ' c ', s%c, ' b ', s%b, ' g ', s%grav, ' k ', s%k, ' box ', s%width, s%height, ' h ', s%h, ' N ', s%nsteps
  end function scene_label

  ! ---- the round trip ----

  !> N steps forward from the pair (q0, q0 + h v0), N back; impacts and energy fallbacks counted in each
  !> direction.
  function round_trip(s) result(r)
    type(reversal_scene_t), intent(in) :: s
    type(reversal_result_t) :: r
    type(reversal_lag_t), target :: lag
    type(reversal_ld_t), target :: ld
    type(vci_integrator_t) :: integ
    integer :: stat
    lag%n = 2; lag%n_gaps = 4; lag%s = s
    ld%n = 2; ld%n_gaps = 4; ld%s = s
    if (s%scheme == VCI_SCHEME_DISCRETE) then
      call integ%create(ld, s%h, stat)
    else
      call integ%create(lag, s%h, stat)
      if (stat == VCI_OK) call integ%set_scheme(s%scheme, s%stages, stat)
    end if
    ! the paper's initial pair (q0, q0 + h v0): Newton's first start is then the motion itself (from
    ! a start at rest, q0 + h 0, the regular step of a strongly quartic L may not converge)
    ! walls poked within one sub-step met in both directions (docs/BACKWARD.md)
    if (stat == VCI_OK) call integ%set_poke_samples(.true., stat)
    if (stat == VCI_OK) call integ%init_from_pair(0.0_dp, s%q0, s%q0 + s%h * s%v0, stat)
    if (stat /= VCI_OK) then
      r%stat = stat; r%message = 'setup: '//integ%message(); return
    end if
    call run(integ, s, r)
  end function round_trip

  !> How much the scene's forward run amplifies a perturbation of its start: N steps from
  !> (q0, q0 + h v0) and from the start with v0 moved by eps |v0| along a fixed direction; the
  !> relative distance of the two ends in (q, p) over eps. A reversal error near
  !> growth * rtol is the scene's chaos acting on the solves' tolerance (docs/BACKWARD.md).
  !> Negative when a run failed.
  real(dp) function forward_growth(s, eps) result(growth)
    type(reversal_scene_t), intent(in) :: s
    real(dp), intent(in) :: eps
    real(dp) :: qa(2), pa(2), qb(2), pb(2)
    type(reversal_scene_t) :: t
    logical :: ok
    growth = -1.0_dp
    call forward_end(s, qa, pa, ok)
    if (.not. ok) return
    t = s
    t%v0 = s%v0 + eps * norm2(s%v0) * [0.6_dp, -0.8_dp]
    call forward_end(t, qb, pb, ok)
    if (.not. ok) return
    growth = max(norm2(qb - qa) / norm2(qa), norm2(pb - pa) / norm2(pa)) / eps
  end function forward_growth

  subroutine forward_end(s, q, p, ok)
    type(reversal_scene_t), intent(in) :: s
    real(dp), intent(out) :: q(2), p(2)
    logical, intent(out) :: ok
    type(reversal_lag_t), target :: lag
    type(reversal_ld_t), target :: ld
    type(vci_integrator_t) :: integ
    integer :: stat, i
    lag%n = 2; lag%n_gaps = 4; lag%s = s
    ld%n = 2; ld%n_gaps = 4; ld%s = s
    if (s%scheme == VCI_SCHEME_DISCRETE) then
      call integ%create(ld, s%h, stat)
    else
      call integ%create(lag, s%h, stat)
      if (stat == VCI_OK) call integ%set_scheme(s%scheme, s%stages, stat)
    end if
    if (stat == VCI_OK) call integ%set_poke_samples(.true., stat)
    if (stat == VCI_OK) call integ%init_from_pair(0.0_dp, s%q0, s%q0 + s%h * s%v0, stat)
    do i = 1, s%nsteps
      if (stat /= VCI_OK) exit
      call integ%step(1, stat)
    end do
    ok = stat == VCI_OK
    q = integ%configuration(); p = integ%momentum()
  end subroutine forward_end

  subroutine run(integ, s, r)
    type(vci_integrator_t), intent(inout) :: integ
    type(reversal_scene_t), intent(in) :: s
    type(reversal_result_t), intent(inout) :: r
    real(dp) :: q0(2), p0(2)
    type(vci_stats_t) :: st
    integer :: stat, i, here, fb
    integer(i8) :: fb0
    q0 = integ%configuration(); p0 = integ%momentum()
    r%multi_steps = 0; r%impacts_fwd = 0; r%impacts_bwd = 0
    fb0 = 0
    do i = 1, s%nsteps
      call integ%step(1, stat)
      if (stat /= VCI_OK) then
        r%stat = stat; r%message = 'forward: '//integ%message()
        st = integ%statistics(); r%fallbacks_fwd = int(st%energy_fallbacks)
        return
      end if
      here = integ%impact_count()
      r%impacts_fwd = r%impacts_fwd + here
      r%touches = r%touches + touches(integ)
      if (here >= 2) r%multi_steps = r%multi_steps + 1
    end do
    st = integ%statistics(); r%fallbacks_fwd = int(st%energy_fallbacks - fb0); fb0 = st%energy_fallbacks
    do i = 1, s%nsteps
      call integ%step(-1, stat)
      if (stat /= VCI_OK) then
        r%stat = stat; r%message = 'backward: '//integ%message()
        st = integ%statistics(); r%fallbacks_bwd = int(st%energy_fallbacks - fb0)
        return
      end if
      r%impacts_bwd = r%impacts_bwd + integ%impact_count()
      r%touches = r%touches + touches(integ)
    end do
    st = integ%statistics(); fb = int(st%energy_fallbacks - fb0); r%fallbacks_bwd = fb
    r%irreversible = int(st%irreversible_impacts)
    r%err_q = norm2(integ%configuration() - q0) / norm2(q0)
    r%err_p = norm2(integ%momentum() - p0) / norm2(p0)
  end subroutine run

  !> Impacts of the last step with no impulse: the free motion from the wall already left it.
  integer function touches(integ)
    type(vci_integrator_t), intent(in) :: integ
    type(vci_impact_t) :: imp
    integer :: i
    touches = 0
    do i = 1, integ%impact_count()
      imp = integ%impact(i)
      if (imp%impulse == 0.0_dp) touches = touches + 1
    end do
  end function touches

  !> The forward run of round_trip, printing each impact: step, time, wall, condition (0 discrete,
  !> 1 H, 2 blended), impulse, the normal velocity before and after (from the momenta at the wall,
  !> L's momentum inverted) and their squares' ratio, which the blended condition sets to
  !> C/(C + 1) (delta > 0) or 1 + 1/C (delta < 0) (docs/BACKWARD.md). Stops at a failed step.
  subroutine print_forward_impacts(s)
    type(reversal_scene_t), intent(in) :: s
    type(reversal_lag_t), target :: lag
    type(vci_integrator_t) :: integ
    type(vci_impact_t) :: imp
    integer :: stat, i, k
    real(dp) :: gn, vb, va
    lag%n = 2; lag%n_gaps = 4; lag%s = s
    call integ%create(lag, s%h, stat)
    if (stat == VCI_OK) call integ%set_scheme(s%scheme, s%stages, stat)
    if (stat == VCI_OK) call integ%set_poke_samples(.true., stat)
    if (stat == VCI_OK) call integ%init_from_pair(0.0_dp, s%q0, s%q0 + s%h * s%v0, stat)
    if (stat /= VCI_OK .or. s%scheme == VCI_SCHEME_DISCRETE) return   ! (the L_d scene: the same L, not printed)
    do i = 1, s%nsteps
      call integ%step(1, stat)
      if (stat /= VCI_OK) then
        print '(a,i0,a,a)', '  step ', i, ' failed: ', trim(integ%message()); return
      end if
      do k = 1, integ%impact_count()
        imp = integ%impact(k)
        gn = norm2(imp%grad_g)
        vb = dot_product(velocity(s, imp%q, imp%p_before), imp%grad_g) / gn
        va = dot_product(velocity(s, imp%q, imp%p_after), imp%grad_g) / gn
        print '(a,i4,a,f9.5,a,i2,a,i2,a,es10.3,a,es10.3,a,es10.3,a,f7.3)', '  step ', i, ' t ', imp%t, ' wall ', imp%gap, &
          ' condition ', imp%condition, ' impulse ', imp%impulse, ' v_n before ', vb, ' after ', va, &
          ' ratio of squares ', (va / vb)**2
      end do
    end do
  end subroutine print_forward_impacts

  !> The velocity whose momentum L_v = v (1 + c |v|^2) + b/2 (-y, x) is p at q (Newton on |v|).
  function velocity(s, q, p) result(v)
    type(reversal_scene_t), intent(in) :: s
    real(dp), intent(in) :: q(2), p(2)
    real(dp) :: v(2), u(2), speed
    integer :: it
    u = p - 0.5_dp * s%b * [-q(2), q(1)]
    speed = norm2(u)
    do it = 1, 60
      speed = speed - (speed * (1.0_dp + s%c * speed**2) - norm2(u)) / (1.0_dp + 3.0_dp * s%c * speed**2)
    end do
    v = u / (1.0_dp + s%c * speed**2)
  end function velocity

  ! ---- L and its partials ----

  real(dp) function lval(s, q, v)
    type(reversal_scene_t), intent(in) :: s
    real(dp), intent(in) :: q(2), v(2)
    real(dp) :: v2
    v2 = sum(v**2)
    lval = 0.5_dp * v2 + 0.25_dp * s%c * v2**2 + 0.5_dp * s%b * (q(1) * v(2) - q(2) * v(1)) &
           - s%grav * q(2) - 0.5_dp * s%k * sum((q - s%qc)**2)
  end function lval

  function lq(s, q, v)
    type(reversal_scene_t), intent(in) :: s
    real(dp), intent(in) :: q(2), v(2)
    real(dp) :: lq(2)
    lq = 0.5_dp * s%b * [v(2), -v(1)] - [0.0_dp, s%grav] - s%k * (q - s%qc)
  end function lq

  function momentum(s, q, v) result(lv)
    type(reversal_scene_t), intent(in) :: s
    real(dp), intent(in) :: q(2), v(2)
    real(dp) :: lv(2)
    lv = v * (1.0_dp + s%c * sum(v**2)) + 0.5_dp * s%b * [-q(2), q(1)]
  end function momentum

  !> H(q, p) = |v|²/2 + 3c|v|⁴/4 + g y + k/2 |q - qc|², v from p = v (1 + c|v|²) + A(q) (Newton on
  !> |v|: s (1 + c s²) = |p - A|, monotone).
  real(dp) function hval(s, q, p)
    type(reversal_scene_t), intent(in) :: s
    real(dp), intent(in) :: q(2), p(2)
    real(dp) :: u(2), un, sp, f
    integer :: it
    u = p - 0.5_dp * s%b * [-q(2), q(1)]
    un = norm2(u); sp = un
    do it = 1, 60
      f = (sp * (1.0_dp + s%c * sp**2) - un) / (1.0_dp + 3.0_dp * s%c * sp**2)
      sp = sp - f
      if (abs(f) <= 1.0e-16_dp * max(sp, tiny(1.0_dp))) exit
    end do
    hval = 0.5_dp * sp**2 + 0.75_dp * s%c * sp**4 + s%grav * q(2) + 0.5_dp * s%k * sum((q - s%qc)**2)
  end function hval

  subroutine rl_lagrangian(self, q, v, l, stat)
    class(reversal_lag_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: l
    integer, intent(inout) :: stat
    l = lval(self%s, q, v)
  end subroutine rl_lagrangian

  subroutine rl_dl_dq(self, q, v, out, stat)
    class(reversal_lag_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = lq(self%s, q, v)
  end subroutine rl_dl_dq

  subroutine rl_dl_dv(self, q, v, out, stat)
    class(reversal_lag_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = momentum(self%s, q, v)
  end subroutine rl_dl_dv

  subroutine rl_hessians(self, q, v, lqq, lqv, lvv, stat)
    class(reversal_lag_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: lqq(:, :), lqv(:, :), lvv(:, :)
    integer, intent(inout) :: stat
    integer :: i
    lqq = 0.0_dp; lqq(1, 1) = -self%s%k; lqq(2, 2) = -self%s%k
    lqv = 0.0_dp; lqv(1, 2) = 0.5_dp * self%s%b; lqv(2, 1) = -0.5_dp * self%s%b
    do i = 1, 2
      lvv(:, i) = 2.0_dp * self%s%c * v * v(i)
      lvv(i, i) = lvv(i, i) + 1.0_dp + self%s%c * sum(v**2)
    end do
  end subroutine rl_hessians

  subroutine rl_energy(self, q, p, e, stat)
    class(reversal_lag_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    e = hval(self%s, q, p)
  end subroutine rl_energy

  ! ---- walls: x >= 0, x <= width, y >= 0, y <= height ----

  subroutine box_gaps(self, q, g, stat)
    class(reversal_lag_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    g = [q(1), self%s%width - q(1), q(2), self%s%height - q(2)]
  end subroutine box_gaps

  subroutine box_gap_grads(self, q, dg, stat)
    class(reversal_lag_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    dg = reshape([1.0_dp, 0.0_dp, -1.0_dp, 0.0_dp, 0.0_dp, 1.0_dp, 0.0_dp, -1.0_dp], [2, 4])
  end subroutine box_gap_grads

  subroutine ld_gaps(self, q, g, stat)
    class(reversal_ld_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    g = [q(1), self%s%width - q(1), q(2), self%s%height - q(2)]
  end subroutine ld_gaps

  subroutine ld_gap_grads(self, q, dg, stat)
    class(reversal_ld_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    dg = reshape([1.0_dp, 0.0_dp, -1.0_dp, 0.0_dp, 0.0_dp, 1.0_dp, 0.0_dp, -1.0_dp], [2, 4])
  end subroutine ld_gap_grads

  ! ---- the midpoint L_d by hand: L_d(q, v, h) = h L((q + v)/2, (v - q)/h) ----

  subroutine ld_d1(self, q, v, h, out, stat)
    class(reversal_ld_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = 0.5_dp * h * lq(self%s, 0.5_dp * (q + v), (v - q) / h) - momentum(self%s, 0.5_dp * (q + v), (v - q) / h)
  end subroutine ld_d1

  subroutine ld_d2(self, q, v, h, out, stat)
    class(reversal_ld_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = 0.5_dp * h * lq(self%s, 0.5_dp * (q + v), (v - q) / h) + momentum(self%s, 0.5_dp * (q + v), (v - q) / h)
  end subroutine ld_d2

  subroutine ld_d3(self, q, v, h, out, stat)
    class(reversal_ld_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out
    integer, intent(inout) :: stat
    real(dp) :: w(2), m(2)
    w = (v - q) / h; m = 0.5_dp * (q + v)
    out = lval(self%s, m, w) - dot_product(momentum(self%s, m, w), w)
  end subroutine ld_d3

  subroutine ld_energy(self, q, p, e, stat)
    class(reversal_ld_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    e = hval(self%s, q, p)
  end subroutine ld_energy
end module vci_test_reversal
