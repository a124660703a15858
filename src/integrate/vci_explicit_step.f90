!> One step of an explicit composition (vci_composition) through elastic impacts (docs/DESIGN.md
!> §9, docs/SCHEMES.md). The regular step is the composed map Φ_h; no linear solve anywhere.
!>
!> Stage 1 (reach the wall): α ∈ (0, 1] with g_j(q(Φ_{αh}(q_k, p_k))) = 0, a scalar root of the
!> gap along the composed map itself (so the impact time has the composition's order). The
!> composition's internal stage ends (times c_i h, some outside [0, h] because of the negative
!> γ_i) are sampled first: the first c_i in (0, 1) whose stage lies beyond the wall, checked on the
!> true map Φ_{c_i h}, closes a bracket [lo, hi] with g > 0 at lo and g < 0 at hi, which Illinois
!> (modified regula falsi) shrinks to round-off. So a path that dips into the wall and out within
!> one step is found when an internal stage sees it (for Verlet, s = 1, only the end is seen),
!> or when the dip screen does: the parabola through the gaps at the sub-step's start, its
!> estimated middle and its end, bend doubled, comes below the wall (may_dip); the true map at its
!> deepest point then decides (dip_bracket). Without it a crossing met at the end one way was a dip
!> that came back out unseen the other way (reversal seeds 112428, 25640, 44182, 48535, 52408).
!> Only the sub-step ends are states: the internal stages are never reflected.
!>
!> Stage 2 (reflect): the Hamiltonian condition H(q̃, p⁺) = H(q̃, p⁻) with p⁺ = p⁻ + μ ∇g_j(q̃). For
!> H = ½ pᵀM⁻¹p + V it is quadratic in μ with the roots 0 and μ = −2 ∇gᵀM⁻¹p⁻ / ∇gᵀM⁻¹∇g: the
!> exact elastic reflection, in closed form. Then Φ_{(1−α)h} from (q̃, p⁺), and again while the
!> end leaves the admissible set (several impacts per step, up to max_impacts_per_step).
!>
!> Backward steps are the same with h → −h: Verlet and its symmetric compositions satisfy
!> Φ_{−h} = Φ_h⁻¹ and the reflection is an involution, so a backward step undoes a forward one up
!> to round-off, impacts included.
module vci_explicit_step
  use vci_kinds, only: dp, i8
  use vci_status
  use vci_message, only: vci_set_message, vci_int_text
  use vci_composition, only: vci_composition_t
  use vci_composition_energy, only: vci_composition_energy_t
  use vci_separable, only: vci_separable_t
  use vci_observer, only: vci_impact_t
  use vci_state, only: vci_impact_buffer_t, vci_state_t
  use vci_scheme, only: VCI_IMPACT_HAMILTONIAN, VCI_IMPACT_DISCRETE
  use vci_settings, only: vci_too_many_impacts_cause, vci_start_beyond_cause, vci_crossed_unseen_cause
  implicit none
  private

  integer, parameter :: ILLINOIS_MAX = 200
  !> A sub-step departing from a wall and ending beyond it: halvings from its end that look for an
  !> admissible point of the true map before the return (first_crossing); 2^-40 of it is round-off
  integer, parameter :: DEPARTURE_HALVINGS = 40
  !> A dip suspected by the screen: maps of the true map at the parabola's deepest point, each
  !> parabola through the true map's points so far (the first through the estimated middle)
  integer, parameter :: DIP_PROBES = 4

  type, public :: vci_explicit_t
    type(vci_composition_t) :: map
    integer :: n = 0, ng = 0
    logical :: start_gaps_known = .false. !< g_start holds the gaps at a
    logical :: samples_known = .false.    !< g_samples holds the gaps at the internal stages
    logical :: middle_known = .false.     !< g_middle holds the gaps at the estimated middle
    integer :: max_impacts = 16           !< the records grow on demand up to it
    integer :: samples = 1                !< sorted(1:samples): stage-end fractions in (0, 1), then 1
    real(dp), allocatable :: a(:), pa(:), qe(:), pe(:), qt(:), pt(:), stage_q(:, :)
    real(dp), allocatable :: q_run(:), p_run(:)   !< explicit_run's step result before it is committed
    real(dp), allocatable :: q_root(:), p_root(:), v_scratch(:)  !< stage 1's last point (fraction root_alpha)
    real(dp), allocatable :: g_sample_min(:)      !< each wall's least gap over the internal stages
    real(dp), allocatable :: g_root(:)            !< every wall's gap at (q_root, p_root)
    real(dp), allocatable :: g_middle(:)          !< every wall's gap at the sub-step's estimated middle
    real(dp) :: root_alpha = -1.0_dp
    !> the last first_crossing's dip (dip_bracket): its probe beyond the wall (fraction, -1: the
    !> crossing was no dip) and the gap there
    real(dp) :: dip_beyond = -1.0_dp, g_dip_beyond = 0.0_dp
    logical :: root_known = .false.
    real(dp), allocatable :: g_start(:), g_end(:), g_trial(:), grad(:), sorted(:), g_samples(:, :)
    integer, allocatable :: order(:)
    integer(i8) :: root_maps = 0      !< composed maps evaluated by stage 1 (statistics)
    !> Stage 2's condition (the integrator's setting, set by the stepper before each step):
    !> VCI_IMPACT_HAMILTONIAN (the mirror, closed form) or VCI_IMPACT_DISCRETE (vci_composition_energy)
    integer :: condition = VCI_IMPACT_HAMILTONIAN
    type(vci_composition_energy_t) :: energy   !< the discrete condition's E_d and its scratch
    integer(i8) :: fallbacks = 0      !< discrete-condition impacts that kept the mirror (a graze)
    !> steps with a suspected dip that the step back from their end did not retrace (dip_check)
    integer(i8) :: irreversible = 0
    logical :: checking = .false.     !< move is the check of a step (no check of the check)
    logical :: step_had_dip = .false. !< the dip screen suspected a wall in this step (may_dip)
    !> screen sub-steps for dips (the integrator's poke-screen setting, set_poke_samples; set by the
    !> stepper before each step): off, only the ends and the samples are checked, as before the screen
    logical :: screen_dips = .true.
    type(vci_impact_buffer_t) :: check_impacts
    real(dp), allocatable :: q_check(:), p_check(:)
    !> The model's one-wall gradient (gap_gradient): 0 not probed yet, 1 provided (O(n) a wall),
    !> 2 not provided (every wall's gradients, O(n n_gaps), for the one wanted)
    integer :: one_wall_gradient = 0
    !> every wall's gradients, only for a model without gap_gradient (allocated at its first use)
    real(dp), allocatable :: all_grads(:, :)
  contains
    procedure :: setup => explicit_setup
    procedure :: advance => explicit_advance
    procedure :: run => explicit_run
  end type vci_explicit_t

contains

  !> Bind the separable model with the composition of the given order. stat: VCI_ERR_ARGUMENT
  !> (order, no mass matrix, constraints), VCI_ERR_MEMORY.
  subroutine explicit_setup(self, model, order, stat)
    class(vci_explicit_t), intent(inout) :: self
    class(vci_separable_t), target, intent(inout) :: model
    integer, intent(in) :: order
    integer, intent(out) :: stat
    integer :: n, ng, s, i, j, k
    call self%map%setup(model, order, stat)
    if (stat /= VCI_OK) return
    n = model%n; ng = max(model%n_gaps, 1); s = self%map%stages
    self%n = n; self%ng = model%n_gaps
    self%one_wall_gradient = 0
    if (allocated(self%a)) deallocate (self%a, self%pa, self%qe, self%pe, self%qt, self%pt, self%stage_q, &
                                       self%g_start, self%g_end, self%g_trial, self%grad, self%sorted, self%order, &
                                       self%g_samples, self%q_run, self%p_run, self%q_root, self%p_root, &
                                       self%v_scratch, self%g_sample_min, self%g_root, self%g_middle, &
                                       self%q_check, self%p_check)
    if (allocated(self%all_grads)) deallocate (self%all_grads)
    allocate (self%q_run(n), self%p_run(n), self%q_root(n), self%p_root(n), self%v_scratch(n), self%g_sample_min(ng), &
              self%g_root(ng), self%g_middle(ng), self%q_check(n), self%p_check(n), &
              self%a(n), self%pa(n), self%qe(n), self%pe(n), self%qt(n), &
              self%pt(n), self%stage_q(n, s), &
              self%g_start(ng), self%g_end(ng), self%g_trial(ng), self%grad(n), self%sorted(s), &
              self%order(s), self%g_samples(ng, s), stat=stat)
    if (stat /= 0) then
      stat = VCI_ERR_MEMORY; return
    end if
    call self%energy%setup(n, stat)
    if (stat /= VCI_OK) return
    ! the internal stage ends inside (0, 1), in increasing time (the last one is the step's end)
    k = 0
    do i = 1, s
      if (self%map%node(i) > 0.0_dp .and. self%map%node(i) < 1.0_dp .and. i < s) then
        k = k + 1; self%order(k) = i
      end if
    end do
    do i = 2, k                     ! insertion sort by node
      j = i
      do while (j > 1)
        if (self%map%node(self%order(j - 1)) <= self%map%node(self%order(j))) exit
        self%order(j - 1:j) = self%order(j:j - 1:-1)
        j = j - 1
      end do
    end do
    self%order(k + 1) = s           ! the end of the step, c = 1
    do i = 1, k
      self%sorted(i) = self%map%node(self%order(i))
    end do
    self%sorted(k + 1) = 1.0_dp
    self%samples = k + 1
    stat = VCI_OK
  end subroutine explicit_setup

  !> One step of length h in direction dir from (q, p) at time t; the result in (q_new, p_new),
  !> e_new = H there; the impacts in `impacts`. On failure stat and cause say why.
  subroutine explicit_advance(self, q, p, h, dir, t, max_impacts, impacts, q_new, p_new, e_new, cause, stat)
    class(vci_explicit_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:), h, t
    integer, intent(in) :: dir, max_impacts
    type(vci_impact_buffer_t), intent(inout) :: impacts
    real(dp), contiguous, intent(out) :: q_new(:), p_new(:)
    real(dp), intent(out) :: e_new
    character(len=*), intent(inout) :: cause
    integer, intent(out) :: stat
    e_new = 0.0_dp
    call move(self, q, p, h, dir, t, max_impacts, impacts, q_new, p_new, cause, stat)
    if (stat /= VCI_OK) return
    call self%map%hamiltonian(q_new, p_new, e_new, stat)
    if (stat /= VCI_OK) call fail(self, 'energy of the new state', stat, cause)
  end subroutine explicit_advance

  !> Up to nsteps steps from the state in direction dir, each taken as explicit_advance takes it
  !> (the same arithmetic: the same bits) and committed as the stepper commits a step (q, p, k,
  !> the impacts' step index), without what nobody reads inside a run: H, the velocity and the
  !> arriving energy are left to the run's last step, which the caller takes on the general path
  !> (vci_integrator's integrate without an observer). Stops before committing a step that fails;
  !> the caller retakes that one on the general path, which reports it. done: steps committed;
  !> found: impacts in them; `impacts` holds the last committed step's.
  subroutine explicit_run(self, state, nsteps, dir, max_impacts, impacts, done, found)
    class(vci_explicit_t), intent(inout) :: self
    type(vci_state_t), intent(inout) :: state
    integer(i8), intent(in) :: nsteps
    integer, intent(in) :: dir, max_impacts
    type(vci_impact_buffer_t), intent(inout) :: impacts
    integer(i8), intent(out) :: done, found
    character(len=VCI_MSG_LEN) :: cause
    integer :: stat, i
    logical :: start_is_last_end, regular
    done = 0; found = 0
    start_is_last_end = .false.
    if (self%ng == 0) then
      ! no walls: the composed map's steps in one kernel (vci_composition's run_steps: flow's
      ! arithmetic, the same bits; a failing step is not taken, its start is in the state)
      impacts%count = 0
      call self%map%run_steps(state%q, state%p, dir * state%h, nsteps, done, stat)
      state%k = state%k + dir * done
      return
    end if
    do while (done < nsteps)
      ! The regular step first, as move takes it (the composed map, the gaps at its end and at the
      ! internal stages): when no wall is reached it is committed here, without move's per-wall
      ! stage-1 set-up; else move goes on from this map (not evaluated twice). The same bits.
      call copy(self%n, state%q, self%qe); call copy(self%n, state%p, self%pe)   ! (move sets a, pa)
      call self%map%flow(self%qe, self%pe, dir * state%h, stat, self%stage_q)
      if (stat == VCI_OK) call gaps(self, self%qe, self%g_end, stat)
      ! (the start's gaps: the last regular step's end's, when that step was committed here)
      self%samples_known = .false.; self%middle_known = .false.; self%start_gaps_known = start_is_last_end
      start_is_last_end = .false.
      if (stat == VCI_OK) call ensure_samples(self, stat)
      regular = .false.
      if (stat == VCI_OK) regular = all_admissible(self%ng, self%g_end, self%g_sample_min)
      if (regular .and. self%screen_dips) then   ! ... unless a wall is crossed and left inside the step
        call ensure_middle(self, state%q, state%p, dir, state%h, stat)
        regular = .not. any_dip(self%ng, self%g_start, self%g_middle, self%g_end)
      end if
      if (stat /= VCI_OK) then
        impacts%count = 0; return             ! the general path retakes the step and reports it
      end if
      if (regular) then
        call copy(self%n, self%qe, state%q); call copy(self%n, self%pe, state%p)
        call copy(self%ng, self%g_end, self%g_start); start_is_last_end = .true.
        impacts%count = 0
        state%k = state%k + dir
        done = done + 1
        cycle
      end if
      call move(self, state%q, state%p, state%h, dir, state%time(), max_impacts, impacts, self%q_run, self%p_run, &
                cause, stat, have_end=.true.)
      if (stat /= VCI_OK) then
        impacts%count = 0; return
      end if
      call copy(self%n, self%q_run, state%q); call copy(self%n, self%p_run, state%p)
      do i = 1, impacts%count
        impacts%records(i)%step = state%k
      end do
      state%k = state%k + dir
      done = done + 1; found = found + impacts%count
    end do
  end subroutine explicit_run

  !> One Illinois step of a bracket on a wall's gap: the point c, gap g, replaces the bracket's end
  !> on its side (g > 0: the admissible end pos, else the end neg beyond the wall); when the same
  !> side is replaced twice running, the other end's gap is halved, so the false position does not
  !> stall at one end. side: the side replaced last (1 admissible, -1 beyond, 0 none yet).
  pure subroutine illinois_narrow(c, g, pos, gpos, neg, gneg, side)
    real(dp), intent(in) :: c, g
    real(dp), intent(inout) :: pos, gpos, neg, gneg
    integer, intent(inout) :: side
    if (g > 0.0_dp) then
      pos = c; gpos = g
      if (side == 1) gneg = 0.5_dp * gneg
      side = 1
    else
      neg = c; gneg = g
      if (side == -1) gpos = 0.5_dp * gpos
      side = -1
    end if
  end subroutine illinois_narrow

  !> Some wall may dip (may_dip) in the sub-step with gaps g0 at its start, gm at its estimated
  !> middle and g1 at its end.
  pure logical function any_dip(ng, g0, gm, g1)
    integer, intent(in) :: ng
    real(dp), intent(in) :: g0(ng), gm(ng), g1(ng)
    integer :: j
    any_dip = .true.
    do j = 1, ng
      if (may_dip(g0(j), gm(j), g1(j))) return
    end do
    any_dip = .false.
  end function any_dip

  !> The screen for a wall crossed and left again inside a sub-step whose start, end and samples
  !> are admissible: the parabola in the fraction c through the gaps g0 (c = 0), gm (c = 1/2, the
  !> estimated middle) and g1 (c = 1), with its bend doubled (the middle is an estimate, O(τ³) off
  !> for a composition, and the gap need not be linear), comes below 0 inside (0, 1).
  pure logical function may_dip(g0, gm, g1)
    real(dp), intent(in) :: g0, gm, g1
    real(dp) :: bend, c
    may_dip = .false.
    bend = 0.5_dp * (g0 + g1) - gm                     ! the middle's depth below the chord
    if (.not. bend > 0.0_dp) return
    c = deepest(g0, g1, 2.0_dp * bend)
    if (c <= 0.0_dp .or. c >= 1.0_dp) return
    may_dip = g0 + (g1 - g0) * c - 8.0_dp * bend * c * (1.0_dp - c) < 0.0_dp
  end function may_dip

  !> The fraction where g0 + (g1 − g0) c − 4 bend c (1 − c) is least (bend > 0).
  pure real(dp) function deepest(g0, g1, bend)
    real(dp), intent(in) :: g0, g1, bend
    deepest = 0.5_dp * (1.0_dp - (g1 - g0) / (4.0_dp * bend))
  end function deepest

  !> No gap negative at the step's end nor at an internal stage (every wall's least sample).
  pure logical function all_admissible(ng, g_end, g_min)
    integer, intent(in) :: ng
    real(dp), intent(in) :: g_end(ng), g_min(ng)
    integer :: j
    all_admissible = .false.
    do j = 1, ng
      if (g_end(j) < 0.0_dp .or. g_min(j) < 0.0_dp) return
    end do
    all_admissible = .true.
  end function all_admissible

  !> The step of explicit_advance without H at its end. have_end: the first sub-step's map from
  !> (q, p) over h is already in (qe, pe, stage_q) with its gaps in g_end and the samples'
  !> (explicit_run's regular step that met a wall).
  recursive subroutine move(self, q, p, h, dir, t, max_impacts, impacts, q_new, p_new, cause, stat, have_end)
    type(vci_explicit_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:), h, t
    integer, intent(in) :: dir, max_impacts
    type(vci_impact_buffer_t), intent(inout) :: impacts
    real(dp), contiguous, intent(out) :: q_new(:), p_new(:)   ! (contiguous: no packing check per step)
    character(len=*), intent(inout) :: cause
    integer, intent(out) :: stat
    logical, intent(in), optional :: have_end
    real(dp) :: tau, elapsed, alpha, best, mu, e_before, e_after, residual
    integer :: j, jj, j0, jbest, condition
    logical :: mapped, accept
    self%max_impacts = max_impacts
    impacts%count = 0
    if (.not. self%checking) self%step_had_dip = .false.
    if (self%ng == 0) then                  ! no walls: the composed map straight into the result
      call copy(self%n, q, q_new); call copy(self%n, p, p_new)
      call self%map%flow(q_new, p_new, dir * h, stat)
      if (stat /= VCI_OK) call fail(self, 'regular step', stat, cause)
      return
    end if
    call copy(self%n, q, self%a); call copy(self%n, p, self%pa)
    tau = h; elapsed = 0.0_dp
    mapped = .false.
    if (present(have_end)) mapped = have_end
    do
      if (.not. mapped) then
        call copy(self%n, self%a, self%qe); call copy(self%n, self%pa, self%pe)
        call self%map%flow(self%qe, self%pe, dir * tau, stat, self%stage_q)
        if (stat /= VCI_OK) then
          call fail(self, 'regular step', stat, cause); return
        end if
        call gaps(self, self%qe, self%g_end, stat)
        if (stat /= VCI_OK) then
          call fail(self, 'gaps of the step''s end', stat, cause); return
        end if
        self%samples_known = .false.; self%middle_known = .false.
      end if
      mapped = .false.
      self%start_gaps_known = .false.       ! (evaluated only when a wall may be crossed)
      self%root_known = .false.
      ! stage 1: the first wall reached along the composed map
      ! The wall met first is searched first (when several are crossed in the sub-step, e.g. a
      ! stretch of a chain): the others are then only checked against its point, whose gaps are
      ! kept (first_crossing), so k walls crossed in one sub-step cost one root search, not k.
      best = 2.0_dp; jbest = 0
      call earliest_candidate(self, j0, stat)
      if (stat /= VCI_OK) then
        call fail(self, 'stage 1 (impact time)', stat, cause); return
      end if
      do jj = 0, self%ng
        j = jj
        if (jj == 0) j = j0
        if (j == 0 .or. (jj > 0 .and. jj == j0)) cycle
        call first_crossing(self, j, dir, tau, best, alpha, stat)
        if (stat == VCI_ERR_INADMISSIBLE .and. impacts%count == 0) then
          call vci_set_message(cause, vci_start_beyond_cause(j, self%g_start(j)))
          return
        else if (stat == VCI_ERR_INADMISSIBLE) then   ! this step's last wall point: stage 1 missed wall j
          stat = VCI_ERR_IMPACT
          call vci_set_message(cause, vci_crossed_unseen_cause(impacts%records(impacts%count)%gap, '', j, self%g_start(j)))
          return
        else if (stat /= VCI_OK) then
          call fail(self, 'stage 1 (impact time)', stat, cause); return
        end if
        if (alpha < best .and. self%dip_beyond > 0.0_dp) then
          call dip_is_impact(self, j, dir, tau, alpha, accept, stat)
          if (stat /= VCI_OK) then
            call fail(self, 'stage 1 (a dip''s ends)', stat, cause); return
          end if
          if (.not. accept) alpha = 2.0_dp
        end if
        if (alpha < best) then
          best = alpha; jbest = j
        end if
      end do
      if (jbest == 0) exit
      if (impacts%count >= max_impacts) then
        stat = VCI_ERR_TOO_MANY_IMPACTS
        cause = vci_too_many_impacts_cause(max_impacts)
        return
      end if
      ! stage 2: the exact reflection at the wall point of the composed map over best * tau
      if (self%root_known .and. self%root_alpha == best) then   ! stage 1 ended on this point
        call copy(self%n, self%q_root, self%qt); call copy(self%n, self%p_root, self%pt)
        stat = VCI_OK
      else
        call copy(self%n, self%a, self%qt); call copy(self%n, self%pa, self%pt)
        stat = VCI_OK
        if (best > 0.0_dp) call self%map%flow(self%qt, self%pt, dir * best * tau, stat)
      end if
      if (stat == VCI_OK) call gap_gradient_of(self, self%qt, jbest, stat)
      if (stat == VCI_OK) call self%map%hamiltonian(self%qt, self%pt, e_before, stat)
      if (stat /= VCI_OK) then
        call fail(self, 'stage 2 (reflection)', stat, cause); return
      end if
      call self%map%model%inverse_mass_times(self%grad, self%qe)   ! qe: M⁻¹∇g (scratch)
      mu = dot_product(self%grad, self%qe)
      if (.not. mu > 0.0_dp) then
        stat = VCI_ERR_IMPACT
        write (cause, '(a,i0,a)') 'stage 2: gradient of gap ', jbest, ' vanishes at the impact point'
        return
      end if
      mu = -2.0_dp * dot_product(self%qe, self%pt) / mu
      condition = VCI_IMPACT_HAMILTONIAN
      if (self%condition == VCI_IMPACT_DISCRETE) then   ! E_d of the arriving sub-step = E_d of the leaving one
        call discrete_condition(self, jbest, dir, best * tau, h - (elapsed + best * tau), mu, e_before, e_after, &
                                residual, condition, stat)
        if (stat /= VCI_OK) then
          call fail(self, 'stage 2 (discrete energy condition)', stat, cause); return
        end if
      end if
      elapsed = elapsed + best * tau
      if (condition == VCI_IMPACT_DISCRETE) then
        call record(self, impacts, dir, h, t, elapsed, jbest, mu, e_before, stat, condition, e_after, residual)
      else
        call record(self, impacts, dir, h, t, elapsed, jbest, mu, e_before, stat)
      end if
      if (stat /= VCI_OK) then
        call fail(self, 'impact record', stat, cause); return
      end if
      self%a = self%qt
      self%pa = self%pt + mu * self%grad
      tau = h - elapsed
    end do
    call copy(self%n, self%qe, q_new); call copy(self%n, self%pe, p_new)
    if (self%step_had_dip .and. .not. self%checking) call dip_check(self, q_new, p_new, h, dir, t, impacts)
  end subroutine move

  !> A step where the dip screen suspected a wall (reflected there or not): the step back from
  !> its end (the other direction's own computation) must meet the same walls in reverse order,
  !> else the step is counted as irreversible (vci_get_irreversible_impacts). A dip is decided on
  !> the map family of each direction's sub-step, and the two families differ by O(τ³): a dip that
  !> shallow is met one way only (reversal seed 110478: 1.5e-5 deep forward, where the entry's
  !> momentum departs, so no impact; 1.7e-4 deep backward, an impact), as a graze shallower than
  !> that is for the implicit schemes' pokes (docs/BACKWARD.md). Reported, not resolved. The
  !> check's own counts are not kept.
  recursive subroutine dip_check(self, q_end, p_end, h, dir, t, impacts)
    type(vci_explicit_t), intent(inout) :: self
    real(dp), intent(in) :: q_end(:), p_end(:), h, t
    integer, intent(in) :: dir
    type(vci_impact_buffer_t), intent(in) :: impacts
    character(len=VCI_MSG_LEN) :: check_cause
    integer(i8) :: fallbacks, root_maps
    integer :: check_stat, i, n
    logical :: same
    call self%check_impacts%reserve(1, self%n, check_stat)   ! (record grows an allocated buffer)
    if (check_stat /= VCI_OK) return
    fallbacks = self%fallbacks; root_maps = self%root_maps
    self%checking = .true.
    check_cause = ''
    call move(self, q_end, p_end, h, -dir, t + real(dir, dp) * h, self%max_impacts, self%check_impacts, &
              self%q_check, self%p_check, check_cause, check_stat)
    self%checking = .false.
    self%fallbacks = fallbacks; self%root_maps = root_maps
    n = impacts%count
    same = check_stat == VCI_OK .and. self%check_impacts%count == n
    if (same) then
      do i = 1, n
        if (self%check_impacts%records(i)%gap /= impacts%records(n + 1 - i)%gap) same = .false.
      end do
    end if
    if (.not. same) self%irreversible = self%irreversible + 1
  end subroutine dip_check

  !> Stage 2 under the discrete condition (vci_composition_energy): e_before = E_d of the arriving
  !> sub-step (from (a, pa) over `before`), mu from the mirror to the root of E_d of the leaving
  !> sub-step (from (qt, pt + μ∇g) over `after`) = e_before. condition: VCI_IMPACT_DISCRETE, or
  !> VCI_IMPACT_HAMILTONIAN when no root contracts near the mirror (a graze: the mirror is kept,
  !> e_before is then H(q̃, p⁻) as the Hamiltonian condition records it, and it is counted).
  subroutine discrete_condition(self, j, dir, before, after, mu, e_before, e_after, residual, condition, stat)
    type(vci_explicit_t), intent(inout) :: self
    integer, intent(in) :: j, dir
    real(dp), intent(in) :: before, after
    real(dp), intent(inout) :: mu, e_before
    real(dp), intent(out) :: e_after, residual
    integer, intent(out) :: condition, stat
    real(dp) :: e_arrive
    logical :: solved
    condition = VCI_IMPACT_HAMILTONIAN; e_after = e_before; residual = 0.0_dp
    call self%energy%step_energy(self%map, self%a, self%pa, dir * before, e_arrive, stat)
    if (stat == VCI_OK) call self%energy%discrete_impulse(self%map, self%qt, self%pt, self%grad, dir * after, &
                                                           e_arrive, mu, e_after, residual, solved, stat)
    if (stat /= VCI_OK) then
      self%map%failed_stat = self%energy%failed_stat; return
    end if
    if (solved) then
      condition = VCI_IMPACT_DISCRETE; e_before = e_arrive
    else
      self%fallbacks = self%fallbacks + 1
    end if
  end subroutine discrete_condition

  !> Stage 1 for wall j on the sub-step of length tau from (a, pa): alpha = the fraction at which
  !> the composed map first reaches g_j = 0, or 2 when it does not within the sub-step (nor before
  !> `limit`, the earliest wall found so far: a crossing after it does not matter).
  subroutine first_crossing(self, j, dir, tau, limit, alpha, stat)
    type(vci_explicit_t), intent(inout) :: self
    integer, intent(in) :: j, dir
    real(dp), intent(in) :: tau, limit
    real(dp), intent(out) :: alpha
    integer, intent(out) :: stat
    real(dp) :: lo, hi, glo, ghi, c, g, gs, slope, delta, delta_prev, floor
    integer :: i, k, nk, side
    logical :: have_lo, any_inside, on_wall, bracketed, dip
    alpha = 2.0_dp; stat = VCI_OK
    self%dip_beyond = -1.0_dp
    nk = self%samples
    call ensure_samples(self, stat)
    if (stat /= VCI_OK) return
    any_inside = self%g_end(j) < 0.0_dp .or. self%g_sample_min(j) < 0.0_dp
    dip = .false.
    if (.not. any_inside) then
      ! end and samples admissible: only a dip can cross the wall (the screen, then the true map)
      if (.not. self%screen_dips) return
      call ensure_middle(self, self%a, self%pa, dir, tau, stat)
      if (stat /= VCI_OK) return
      if (.not. may_dip(self%g_start(j), self%g_middle(j), self%g_end(j))) return
      dip = .true.
      if (.not. self%checking) self%step_had_dip = .true.     ! (checked from the step's end: dip_check)
    end if
    ! A start on the wall (after a reflection, or a step that ended on it), to within the rounding
    ! of g there: moving into it, reflect at once; departing from it, the bracket's low end is the
    ! first point of the true map that is admissible again, and only the end can show a return
    ! (internal stages close to the start scatter around g = 0 by their low-order error).
    if (.not. self%start_gaps_known) then
      call gaps(self, self%a, self%g_start, stat)
      if (stat /= VCI_OK) return
      self%start_gaps_known = .true.
    end if
    call gap_gradient_of(self, self%a, j, stat)
    if (stat /= VCI_OK) return
    on_wall = self%g_start(j) <= 64.0_dp * epsilon(1.0_dp) * sum(abs(self%grad) * max(abs(self%a), 1.0_dp))
    ! Beyond the wall by more than g's rounding (sqrt(eps) of its terms, far above the 64 eps of a
    ! wall point): not "on" it (that reflected from inside it with status OK) but a status, which
    ! move words: the step's start was accepted with every gap >= 0, so at the step's start the
    ! gap callback is not a function of q alone (or the model changed); at a later sub-step's
    ! start, this step's last wall point, stage 1 missed wall j
    if (self%g_start(j) < -sqrt(epsilon(1.0_dp)) * sum(abs(self%grad) * max(abs(self%a), 1.0_dp))) then
      stat = VCI_ERR_INADMISSIBLE; return
    end if
    if (dip .and. on_wall) return                ! (a start on the wall: as before the screen)
    if (on_wall) then
      call self%map%model%inverse_mass_times(self%pa, self%qt)
      if (dir * dot_product(self%grad, self%qt) < 0.0_dp) then
        alpha = 0.0_dp; return
      end if
      if (.not. self%g_end(j) < 0.0_dp) return
    end if
    have_lo = .not. on_wall
    lo = 0.0_dp; glo = self%g_start(j)
    hi = -1.0_dp
    bracketed = .false.
    if (dip) then
      call dip_bracket(self, j, dir, tau, lo, glo, hi, ghi, stat)
      if (stat /= VCI_OK) return
      if (hi < 0.0_dp .or. lo >= limit) return   ! no crossing on the true map, or after a wall found
      if (ghi == 0.0_dp) then
        alpha = hi; return                        ! (a probe on the wall: a touch, not a dip's entry)
      end if
      bracketed = .true.
      self%dip_beyond = hi; self%g_dip_beyond = ghi
    end if
    if (on_wall) then
      ! Departing from the wall and ending beyond it: the forces bring the motion back within the
      ! sub-step (a soft reflection). The samples near the start scatter around g = 0 and Verlet
      ! has none, so none may serve as the bracket's admissible end: without one the sub-step
      ! ended beyond the wall, and the next steps reflected from inside it (C reversal seed 4986:
      ! gaps down to -9.4e-3, another path in each direction). The return is bracketed on the true
      ! map by halving from the end: the largest c = 2^-k with g > 0, and 2c beyond the wall.
      hi = 1.0_dp; ghi = self%g_end(j)
      glo = -1.0_dp                              ! (the start's gap may be a rounding above 0)
      do k = 1, DEPARTURE_HALVINGS
        c = 0.5_dp * hi
        call gap_on_map(self, j, dir, c * tau, g, stat)
        if (stat /= VCI_OK) return
        if (g > 0.0_dp) then
          lo = c; glo = g; exit
        else if (g == 0.0_dp) then
          call keep_root(self, c); alpha = c; return
        end if
        hi = c; ghi = g
      end do
      if (.not. glo > 0.0_dp) return             ! back within 2^-40 of the sub-step: round-off
      if (lo >= limit) return                    ! a wall already found comes first
      bracketed = .true.
    end if
    if (.not. bracketed) then
      do k = 1, nk
        c = self%sorted(k)
        if (c >= limit) then
          ! A wall already found comes first, unless this one is crossed between its last admissible
          ! sample and that wall's point: the gap there on the true map decides (samples are sparse,
          ! Verlet has none inside a step; without this the earlier crossing was reflected late).
          if (.not. have_lo .or. on_wall) return
          if (.not. (self%root_known .and. self%root_alpha == limit)) then   ! that point's map, once
            call gap_on_map(self, j, dir, limit * tau, g, stat)
            if (stat /= VCI_OK) return
            call keep_root(self, limit)
          end if
          g = self%g_root(j)
          if (.not. g < 0.0_dp) return
          hi = limit; ghi = g; exit
        end if
        if (k < nk .and. have_lo) then
          if (on_wall .or. self%g_samples(j, k) >= 0.0_dp) cycle   ! admissible sample: no need of the true map
        end if
        if (k == nk) then
          g = self%g_end(j)                      ! c = 1: the step's own end, already on the true map
        else
          call gap_on_map(self, j, dir, c * tau, g, stat)
          if (stat /= VCI_OK) return
        end if
        if (g > 0.0_dp) then
          have_lo = .true.; lo = c; glo = g
        else if (have_lo) then
          hi = c; ghi = g; exit
        end if
      end do
    end if
    if (hi < 0.0_dp) return                    ! never departed or never came back
    if (ghi == 0.0_dp) then
      alpha = hi; return
    end if
    ! Newton along the composed map inside the bracket [lo, hi] (g(lo) > 0 > g(hi)): the slope of
    ! α ↦ g_j(q(Φ_{ατ})) is dir τ ∇g_jᵀ M⁻¹ p there up to the composition's error, so Newton
    ! converges linearly at a tiny rate and its first point, the root of the cubic Hermite
    ! interpolant of g and its slope at the sub-step's ends (both on the true map), is already
    ! close. A point outside the bracket is replaced by Illinois's (modified regula falsi).
    ! Accepted: a point where the correction is round-off, or the next point when the observed
    ! rate says its error is (its map is the one stage 2 needs anyway).
    call hermite_start(self, j, dir, tau, lo, hi, c, stat)
    if (stat /= VCI_OK) return
    side = 0; delta_prev = 0.0_dp; floor = 0.0_dp
    do i = 1, ILLINOIS_MAX
      if (.not. (c > lo .and. c < hi)) then
        c = (lo * ghi - hi * glo) / (ghi - glo)
        if (.not. (c > lo .and. c < hi)) c = 0.5_dp * (lo + hi)
        if (c <= lo .or. c >= hi) exit        ! no floating-point number left between the ends
      end if
      call gap_on_map(self, j, dir, c * tau, gs, stat)
      if (stat /= VCI_OK) return
      if (gs == 0.0_dp) then
        call keep_root(self, c); alpha = c; return
      else
        call illinois_narrow(c, gs, lo, glo, hi, ghi, side)
      end if
      call slope_on_map(self, j, dir, tau, slope, stat)
      if (stat /= VCI_OK) return
      delta = -gs / slope
      if (.not. abs(delta) <= huge(1.0_dp)) then
        c = -1.0_dp; delta_prev = 0.0_dp           ! no usable slope: Illinois's point next
        cycle
      end if
      if (abs(delta) <= 4.0_dp * epsilon(1.0_dp) * c) then
        call keep_root(self, c); alpha = c; return
      end if
      ! The gap's rounding at this point, as a fraction: below it the computed g is noise and a
      ! test relative to c (small when the wall is met early in the sub-step) is out of reach.
      ! When Newton's correction is within it and no longer contracting, c is a root to the
      ! precision g has: accept it if admissible, else the admissible end of the bracket if that
      ! is as close (else go on: the next point lands on either side of the noisy root).
      ! (At most √ε: a graze, slope → 0, leaves the root that ill-determined anyway.)
      floor = min(8.0_dp * epsilon(1.0_dp) * sum(abs(self%grad) * abs(self%qt)) / abs(slope), &
                  sqrt(epsilon(1.0_dp)))
      if (abs(delta) <= floor .and. delta_prev /= 0.0_dp .and. abs(delta) > 0.5_dp * abs(delta_prev)) then
        if (gs > 0.0_dp) then
          call keep_root(self, c); alpha = c; return
        else if (c - lo <= 2.0_dp * floor) then
          alpha = lo; return                      ! (its state: stage 2's map)
        end if
      end if
      if (delta_prev /= 0.0_dp .and. abs(delta) < abs(delta_prev)) then
        if (abs(delta / delta_prev) * abs(delta) <= 4.0_dp * epsilon(1.0_dp) * c .and. &
            c + delta > lo .and. c + delta < hi) then
          alpha = c + delta; return               ! (its state: stage 2's map)
        end if
      end if
      delta_prev = delta
      c = c + delta
      if (hi - lo <= 2.0_dp * epsilon(1.0_dp) * hi .or. hi - lo <= floor) exit
    end do
    alpha = lo                                 ! the admissible side of the crossing
  end subroutine first_crossing

  !> Every wall's gap at the start (q0, p0) of the sub-step of length tau (g_start) and at its
  !> estimated middle (g_middle), once per sub-step: q(1/2) of the quadratic in the fraction c
  !> through q0 with slope dir τ M⁻¹p0 there and through the end qe at c = 1, (3 q0 + qe +
  !> dir τ M⁻¹p0)/4. Verlet's map over c τ is exactly that quadratic (kick–drift–kick); a
  !> composition's is to O(τ³). No force: one product with M⁻¹ and one gaps callback.
  subroutine ensure_middle(self, q0, p0, dir, tau, stat)
    type(vci_explicit_t), intent(inout) :: self
    real(dp), intent(in) :: q0(:), p0(:), tau
    integer, intent(in) :: dir
    integer, intent(out) :: stat
    integer :: i
    stat = VCI_OK
    if (self%middle_known) return
    if (.not. self%start_gaps_known) then
      call gaps(self, q0, self%g_start, stat)
      if (stat /= VCI_OK) return
      self%start_gaps_known = .true.
    end if
    call self%map%model%inverse_mass_times(p0, self%v_scratch)
    do i = 1, self%n
      self%v_scratch(i) = 0.25_dp * ((3.0_dp * q0(i) + self%qe(i)) + dir * tau * self%v_scratch(i))
    end do
    call gaps(self, self%v_scratch, self%g_middle, stat)
    if (stat == VCI_OK) self%middle_known = .true.
  end subroutine ensure_middle

  !> A dip of wall j suspected by the screen (may_dip), on the true map: the map at the deepest
  !> point of the screen's parabola (without the doubling), then at the vertex of the parabola
  !> through the true map's three points around the least gap so far, while that vertex lies
  !> below the wall, up to DIP_PROBES maps. hi < 0: no crossing found (the dip stays above the
  !> wall, to the parabola's resolution); else g > 0 at lo (the start or a probe), g <= 0 at hi.
  subroutine dip_bracket(self, j, dir, tau, lo, glo, hi, ghi, stat)
    type(vci_explicit_t), intent(inout) :: self
    integer, intent(in) :: j, dir
    real(dp), intent(in) :: tau
    real(dp), intent(out) :: lo, glo, hi, ghi
    integer, intent(out) :: stat
    real(dp) :: cs(3), gs(3), c, g, bend
    integer :: k
    lo = 0.0_dp; glo = self%g_start(j); hi = -1.0_dp; ghi = 0.0_dp
    cs = [0.0_dp, 0.5_dp, 1.0_dp]; gs = [self%g_start(j), self%g_middle(j), self%g_end(j)]
    bend = 0.5_dp * (gs(1) + gs(3)) - gs(2)
    c = deepest(gs(1), gs(3), bend)
    if (c <= 0.0_dp .or. c >= 1.0_dp) c = deepest(gs(1), gs(3), 2.0_dp * bend)
    do k = 1, DIP_PROBES
      call gap_on_map(self, j, dir, c * tau, g, stat)
      if (stat /= VCI_OK) return
      if (.not. g > 0.0_dp) then
        hi = c; ghi = g
        if (g == 0.0_dp) call keep_root(self, c)
        return
      end if
      ! the three true-map points around the least gap (the estimated middle drops out first)
      if (k == 1) then
        cs(2) = c; gs(2) = g
      else if (c < cs(2)) then
        if (g < gs(2)) then
          cs(3) = cs(2); gs(3) = gs(2); cs(2) = c; gs(2) = g
        else
          cs(1) = c; gs(1) = g
        end if
      else
        if (g < gs(2)) then
          cs(1) = cs(2); gs(1) = gs(2); cs(2) = c; gs(2) = g
        else
          cs(3) = c; gs(3) = g
        end if
      end if
      if (.not. parabola_vertex(cs, gs, c)) return
    end do
  contains
    !> The vertex of the parabola through (cs(i), gs(i)), when it opens upwards, lies strictly
    !> between cs(1) and cs(3) and below the wall.
    logical function parabola_vertex(cs, gs, c)
      real(dp), intent(in) :: cs(3), gs(3)
      real(dp), intent(out) :: c
      real(dp) :: d1, d2, curv
      parabola_vertex = .false.; c = -1.0_dp
      d1 = (gs(2) - gs(1)) / (cs(2) - cs(1)); d2 = (gs(3) - gs(2)) / (cs(3) - cs(2))
      curv = (d2 - d1) / (cs(3) - cs(1))
      if (.not. curv > 0.0_dp) return
      c = 0.5_dp * (cs(1) + cs(2)) - 0.5_dp * d1 / curv
      if (.not. (c > cs(1) .and. c < cs(3))) return
      parabola_vertex = gs(1) + d1 * (c - cs(1)) + curv * (c - cs(1)) * (c - cs(2)) < 0.0_dp
    end function parabola_vertex
  end subroutine dip_bracket

  !> A dip of wall j found by stage 1 (entry at alpha, the probe dip_beyond beyond the wall) is an
  !> impact only when the momentum agrees with the map's crossing at both of its ends: arriving
  !> at the wall where the map enters it, departing where the map leaves it (the root between the
  !> probe and the sub-step's end, by Illinois to round-off). The map's slope in the fraction and
  !> the momentum differ by O(τ²) (Verlet: c τ/2 M⁻¹(∇V(q_c) − ∇V(q_0))), and at a graze that
  !> shallow they disagree in sign: the mirror at such an entry pushed into the wall (reversal
  !> seed 110478: impulse −0.039 forward, while the backward run, entering the same dip at its
  !> other end, reflected with +0.043). The condition at both ends reads the same both ways.
  subroutine dip_is_impact(self, j, dir, tau, alpha, accept, stat)
    type(vci_explicit_t), intent(inout) :: self
    integer, intent(in) :: j, dir
    real(dp), intent(in) :: tau, alpha
    logical, intent(out) :: accept
    integer, intent(out) :: stat
    integer, parameter :: EXIT_ITERATIONS = 100
    real(dp) :: g, a, b, ga, gb, c, rate
    integer :: i, side
    accept = .false.
    if (self%root_known .and. self%root_alpha == alpha) then
      call copy(self%n, self%q_root, self%qt); call copy(self%n, self%p_root, self%pt)
      stat = VCI_OK
    else
      call gap_on_map(self, j, dir, alpha * tau, g, stat)
    end if
    if (stat == VCI_OK) call slope_on_map(self, j, dir, tau, rate, stat)
    if (stat /= VCI_OK .or. .not. rate < 0.0_dp) return           ! departing at the entry
    a = self%dip_beyond; ga = self%g_dip_beyond; b = 1.0_dp; gb = self%g_end(j)
    side = 0
    do i = 1, EXIT_ITERATIONS
      c = (a * gb - b * ga) / (gb - ga)
      if (.not. (c > a .and. c < b)) c = 0.5_dp * (a + b)
      if (c <= a .or. c >= b) exit
      call gap_on_map(self, j, dir, c * tau, g, stat)
      if (stat /= VCI_OK) return
      call illinois_narrow(c, g, b, gb, a, ga, side)
      if (b - a <= 4.0_dp * epsilon(1.0_dp) * b) exit
    end do
    call gap_on_map(self, j, dir, b * tau, g, stat)               ! the exit's admissible side
    if (stat == VCI_OK) call slope_on_map(self, j, dir, tau, rate, stat)
    accept = stat == VCI_OK .and. rate > 0.0_dp
  end subroutine dip_is_impact

  !> Every wall's gap at every internal stage of the sub-step (once per sub-step).
  subroutine ensure_samples(self, stat)
    type(vci_explicit_t), intent(inout) :: self
    integer, intent(out) :: stat
    integer :: cb
    logical :: finite
    stat = VCI_OK
    if (self%samples_known) return
    call sample_stages(self%map%model, self%n, self%ng, self%samples - 1, self%order, self%stage_q, self%g_samples, &
                       self%g_sample_min, cb, finite)
    call callback_status(self, cb, finite, stat)
    if (stat == VCI_OK) self%samples_known = .true.
  end subroutine ensure_samples

  !> j0: the wall whose gap turns negative first along the sub-step, by linear interpolation
  !> between the last admissible point (the start or a sample) and the first one beyond the wall
  !> (a sample or the end); 0 when no wall is crossed at a sample or the end. An estimate only,
  !> for the order of the searches: a wall crossed earlier is still found by its check.
  subroutine earliest_candidate(self, j0, stat)
    type(vci_explicit_t), intent(inout) :: self
    integer, intent(out) :: j0
    integer, intent(out) :: stat
    integer :: j, k, inside, nk
    real(dp) :: est, best_est, c_prev, g_prev, c_in, g_in
    j0 = 0; inside = 0
    call ensure_samples(self, stat)
    if (stat /= VCI_OK) return
    do j = 1, self%ng
      if (self%g_end(j) < 0.0_dp .or. self%g_sample_min(j) < 0.0_dp) then
        inside = inside + 1; j0 = j
      end if
    end do
    if (inside <= 1) return          ! one wall or none: nothing to order
    if (.not. self%start_gaps_known) then
      call gaps(self, self%a, self%g_start, stat)
      if (stat /= VCI_OK) return
      self%start_gaps_known = .true.
    end if
    nk = self%samples
    best_est = huge(1.0_dp); j0 = 0
    do j = 1, self%ng
      if (.not. (self%g_end(j) < 0.0_dp .or. self%g_sample_min(j) < 0.0_dp)) cycle
      c_prev = 0.0_dp; g_prev = self%g_start(j)
      c_in = 1.0_dp; g_in = self%g_end(j)
      do k = 1, nk - 1
        if (self%g_samples(j, k) < 0.0_dp) then
          c_in = self%sorted(k); g_in = self%g_samples(j, k); exit
        end if
        c_prev = self%sorted(k); g_prev = self%g_samples(j, k)
      end do
      est = c_prev
      if (g_prev > 0.0_dp) est = c_prev + (c_in - c_prev) * g_prev / (g_prev - g_in)
      if (est < best_est) then
        best_est = est; j0 = j
      end if
    end do
  end subroutine earliest_candidate

  !> Stage 1's first point in (lo, hi) for wall j: the root there of the cubic Hermite interpolant
  !> of α ↦ g_j on [0, 1] from g and its slope (dir τ ∇g_jᵀ M⁻¹ p) at the sub-step's start (a, pa)
  !> and end (qe, pe), both states of the true map; -1 (Illinois's point) when the cubic does
  !> not change sign on [lo, hi]. A few safeguarded Newton steps on the cubic (arithmetic only).
  subroutine hermite_start(self, j, dir, tau, lo, hi, c, stat)
    type(vci_explicit_t), intent(inout) :: self
    integer, intent(in) :: j, dir
    real(dp), intent(in) :: tau, lo, hi
    real(dp), intent(out) :: c
    integer, intent(out) :: stat
    real(dp) :: g0, g1, d0, d1, a, b, fa, fb, f, df
    integer :: i
    c = -1.0_dp
    call gap_gradient_of(self, self%a, j, stat)
    if (stat /= VCI_OK) return
    call self%map%model%inverse_mass_times(self%pa, self%qt)
    d0 = dir * tau * dot_product(self%grad, self%qt)
    call gap_gradient_of(self, self%qe, j, stat)
    if (stat /= VCI_OK) return
    call self%map%model%inverse_mass_times(self%pe, self%qt)
    d1 = dir * tau * dot_product(self%grad, self%qt)
    g0 = self%g_start(j); g1 = self%g_end(j)
    a = lo; b = hi
    fa = cubic(a); fb = cubic(b)
    if (.not. (fa > 0.0_dp .and. fb < 0.0_dp)) return
    c = 0.5_dp * (a + b)
    do i = 1, 30
      f = cubic(c)
      if (f > 0.0_dp) then
        a = c
      else
        b = c
      end if
      df = (6.0_dp * g0 - 6.0_dp * g1 + 3.0_dp * d0 + 3.0_dp * d1) * c**2 &
           + (-6.0_dp * g0 + 6.0_dp * g1 - 4.0_dp * d0 - 2.0_dp * d1) * c + d0
      c = c - f / df
      if (.not. (c > a .and. c < b)) c = 0.5_dp * (a + b)
      if (b - a <= 1.0e-3_dp * abs(f / df) .or. abs(f / df) <= epsilon(1.0_dp) * c) exit
    end do
  contains
    real(dp) function cubic(x)
      real(dp), intent(in) :: x
      cubic = (2.0_dp * x**3 - 3.0_dp * x**2 + 1.0_dp) * g0 + (x**3 - 2.0_dp * x**2 + x) * d0 &
              + (-2.0_dp * x**3 + 3.0_dp * x**2) * g1 + (x**3 - x**2) * d1
    end function cubic
  end subroutine hermite_start

  !> d/dα of g_j(q(Φ_{ατ})) at the state (qt, pt) of the last gap_on_map, to the composition's
  !> error: dir τ ∇g_j(qt)ᵀ M⁻¹ pt.
  subroutine slope_on_map(self, j, dir, tau, slope, stat)
    type(vci_explicit_t), intent(inout) :: self
    integer, intent(in) :: j, dir
    real(dp), intent(in) :: tau
    real(dp), intent(out) :: slope
    integer, intent(out) :: stat
    slope = 0.0_dp
    call gap_gradient_of(self, self%qt, j, stat)
    if (stat /= VCI_OK) return
    call self%map%model%inverse_mass_times(self%pt, self%v_scratch)
    slope = dir * tau * dot_product(self%grad, self%v_scratch)
  end subroutine slope_on_map

  !> Stage 1 ends on the point of the last gap_on_map (fraction c): keep its state for stage 2
  !> and every wall's gap there (the other walls are checked against it).
  subroutine keep_root(self, c)
    type(vci_explicit_t), intent(inout) :: self
    real(dp), intent(in) :: c
    call copy(self%n, self%qt, self%q_root); call copy(self%n, self%pt, self%p_root)
    call copy(self%ng, self%g_trial, self%g_root)
    self%root_alpha = c; self%root_known = .true.
  end subroutine keep_root

  !> g_j at the end of the composed map over the fraction `frac_tau` from (a, pa).
  subroutine gap_on_map(self, j, dir, frac_tau, g, stat)
    type(vci_explicit_t), intent(inout) :: self
    integer, intent(in) :: j, dir
    real(dp), intent(in) :: frac_tau
    real(dp), intent(out) :: g
    integer, intent(out) :: stat
    self%qt = self%a; self%pt = self%pa
    self%root_maps = self%root_maps + 1
    call self%map%flow(self%qt, self%pt, dir * frac_tau, stat)
    if (stat /= VCI_OK) return
    call gaps(self, self%qt, self%g_trial, stat)
    g = self%g_trial(j)
  end subroutine gap_on_map

  !> The gaps at the internal stage ends stage_q(:, order(k)), k = 1 … nk, into g_samples(:, k):
  !> one callback per stage on explicit-shape storage (this runs on every step of a walled run).
  !> cb: the callback's code (0: ok); finite: every gap finite.
  subroutine sample_stages(model, n, ng, nk, order, stage_q, g_samples, g_min, cb, finite)
    class(vci_separable_t), intent(inout) :: model
    integer, intent(in) :: n, ng, nk, order(*)
    real(dp), intent(in) :: stage_q(n, *)
    real(dp), intent(inout) :: g_samples(ng, *)
    real(dp), intent(out) :: g_min(ng)         !< each wall's least sampled gap (huge: none sampled)
    integer, intent(out) :: cb
    logical, intent(out) :: finite
    integer :: k, i
    cb = 0; finite = .true.
    g_min = huge(1.0_dp)
    do k = 1, nk
      call model%gaps(stage_q(:, order(k)), g_samples(:, k), cb)
      if (cb /= 0) return
      do i = 1, ng
        if (.not. abs(g_samples(i, k)) <= huge(1.0_dp)) finite = .false.
        g_min(i) = min(g_min(i), g_samples(i, k))
      end do
    end do
  end subroutine sample_stages

  !> dst = src (explicit shape: a plain loop, not a descriptor-driven copy).
  pure subroutine copy(n, src, dst)
    integer, intent(in) :: n
    real(dp), intent(in) :: src(n)
    real(dp), intent(out) :: dst(n)
    integer :: j
    do j = 1, n
      dst(j) = src(j)
    end do
  end subroutine copy

  subroutine gaps(self, q, g, stat)
    type(vci_explicit_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(out) :: stat
    integer :: s
    s = 0
    call self%map%model%gaps(q, g(1:self%ng), s)
    call callback_status(self, s, all(abs(g(1:self%ng)) <= huge(1.0_dp)), stat)
  end subroutine gaps

  !> grad = the gradient of wall j's gap at q (every use reads the wall it just asked for): the
  !> model's one-wall gradient when it has one (probed at the first call), else column j of every
  !> wall's (all_grads, n x n_gaps, allocated then only: VCI_ERR_MEMORY when that fails).
  !> A chain of n particles has 2n walls: all gradients would cost O(n^2) per call.
  subroutine gap_gradient_of(self, q, j, stat)
    type(vci_explicit_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    integer, intent(in) :: j
    integer, intent(out) :: stat
    integer :: s
    s = 0
    if (self%one_wall_gradient /= 2) then
      if (self%one_wall_gradient == 0) call self%map%model%clear_not_provided()
      call self%map%model%gap_gradient(q, j, self%grad, s)
      if (self%one_wall_gradient == 0) then
        self%one_wall_gradient = merge(2, 1, self%map%model%answered_not_provided())
        if (self%one_wall_gradient == 2) s = 0
      end if
    end if
    if (self%one_wall_gradient == 2) then
      if (.not. allocated(self%all_grads)) then
        allocate (self%all_grads(self%n, self%ng), stat=s)
        if (s /= 0) then
          self%grad = 0.0_dp; stat = VCI_ERR_MEMORY; return
        end if
      end if
      call self%map%model%gap_gradients(q, self%all_grads, s)
      self%grad = self%all_grads(:, j)
    end if
    call callback_status(self, s, all(abs(self%grad) <= huge(1.0_dp)), stat)
  end subroutine gap_gradient_of

  subroutine callback_status(self, s, finite, stat)
    type(vci_explicit_t), intent(inout) :: self
    integer, intent(in) :: s
    logical, intent(in) :: finite
    integer, intent(out) :: stat
    stat = VCI_OK
    if (s /= 0) then
      self%map%failed_stat = s; stat = VCI_ERR_CALLBACK
    else if (.not. finite) then
      stat = VCI_ERR_NONFINITE
    end if
  end subroutine callback_status

  !> The impact just resolved (the wall point in qt, p⁻ in pt), as the other schemes record it.
  !> With condition (VCI_IMPACT_DISCRETE): e_before, e_after are the sub-steps' E_d, residual
  !> the energy row's |E_d⁺ − E_d⁻| relative to the energy's size.
  subroutine record(self, impacts, dir, h, t, elapsed, j, mu, e_before, stat, condition, e_discrete_after, residual)
    type(vci_explicit_t), intent(inout) :: self
    type(vci_impact_buffer_t), intent(inout) :: impacts
    integer, intent(in) :: dir, j
    real(dp), intent(in) :: h, t, elapsed, mu, e_before
    integer, intent(out) :: stat
    integer, intent(in), optional :: condition
    real(dp), intent(in), optional :: e_discrete_after, residual
    real(dp) :: e_after
    stat = VCI_OK
    if (impacts%count >= size(impacts%records)) then
      call impacts%reserve(min(2 * size(impacts%records) + 1, self%max_impacts), self%n, stat)
      if (stat /= VCI_OK) return
    end if
    impacts%count = impacts%count + 1
    associate (imp => impacts%records(impacts%count))
      imp%t = t + real(dir, dp) * elapsed
      imp%alpha = elapsed / h
      imp%gap = j
      imp%q = self%qt
      imp%p_before = self%pt
      imp%p_after = self%pt + mu * self%grad
      imp%grad_g = self%grad
      imp%impulse = real(dir, dp) * mu
      imp%condition = VCI_IMPACT_HAMILTONIAN
      imp%energy_before = e_before
      call self%map%hamiltonian(self%qt, imp%p_after, e_after, stat)
      imp%energy_after = e_after
      call self%map%model%inverse_mass_times(imp%p_after, self%qe)
      imp%leave_rate = real(dir, dp) * dot_product(self%grad, self%qe)
      imp%stage1_residual = 0.0_dp
      imp%stage2_residual = 0.0_dp
      if (present(condition)) then
        imp%condition = condition
        imp%energy_after = e_discrete_after
        imp%stage2_residual = residual / (16.0_dp * epsilon(1.0_dp))   ! (<= 1: within 16 ulps of the energy)
      end if
    end associate
  end subroutine record

  subroutine fail(self, what, stat, cause)
    type(vci_explicit_t), intent(in) :: self
    character(len=*), intent(in) :: what
    integer, intent(in) :: stat
    character(len=*), intent(inout) :: cause
    select case (stat)
    case (VCI_ERR_CALLBACK)
      call vci_set_message(cause, what//': a callback of the model reported failure (stat = '// &
        trim(vci_int_text(self%map%failed_stat))//')')
    case (VCI_ERR_NONFINITE)
      cause = what//': a callback of the model returned NaN or Inf'
    case (VCI_ERR_MEMORY)
      cause = what//': out of memory'
    case default
      cause = what//' failed'
    end select
  end subroutine fail
end module vci_explicit_step
