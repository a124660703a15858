!> One step of an explicit composition (vci_composition) through elastic impacts (docs/DESIGN.md
!> §9, docs/SCHEMES.md). The regular step is the composed map Φ_h; no linear solve anywhere.
!>
!> Stage 1 (reach the wall): α ∈ (0, 1] with g_j(q(Φ_{αh}(q_k, p_k))) = 0, a scalar root of the
!> gap along the composed map itself (so the impact time has the composition's order). The
!> composition's internal stage ends (times c_i h, some outside [0, h] because of the negative
!> γ_i) are sampled first: the first c_i in (0, 1) whose stage lies beyond the wall, checked on the
!> true map Φ_{c_i h}, closes a bracket [lo, hi] with g > 0 at lo and g < 0 at hi, which Illinois
!> (modified regula falsi) shrinks to round-off. So a path that dips into the wall and out within
!> one step is found when an internal stage sees it (for Verlet, s = 1, only the end is seen).
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
  use vci_composition, only: vci_composition_t
  use vci_separable, only: vci_separable_t
  use vci_observer, only: vci_impact_t
  use vci_state, only: vci_impact_buffer_t
  use vci_scheme, only: VCI_IMPACT_HAMILTONIAN
  implicit none
  private

  integer, parameter :: ILLINOIS_MAX = 200

  type, public :: vci_explicit_t
    type(vci_composition_t) :: map
    integer :: n = 0, ng = 0
    logical :: start_gaps_known = .false. !< g_start holds the gaps at a
    logical :: samples_known = .false.    !< g_samples holds the gaps at the internal stages
    integer :: max_impacts = 16           !< the records grow on demand up to it
    integer :: samples = 1                !< sorted(1:samples): stage-end fractions in (0, 1), then 1
    real(dp), allocatable :: a(:), pa(:), qe(:), pe(:), qt(:), pt(:), stage_q(:, :)
    real(dp), allocatable :: g_start(:), g_end(:), g_trial(:), grads(:, :), sorted(:), g_samples(:, :)
    integer, allocatable :: order(:)
    integer(i8) :: root_maps = 0      !< composed maps evaluated by stage 1 (statistics)
  contains
    procedure :: setup => explicit_setup
    procedure :: advance => explicit_advance
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
    if (allocated(self%a)) deallocate (self%a, self%pa, self%qe, self%pe, self%qt, self%pt, self%stage_q, &
                                       self%g_start, self%g_end, self%g_trial, self%grads, self%sorted, self%order, &
                                       self%g_samples)
    allocate (self%a(n), self%pa(n), self%qe(n), self%pe(n), self%qt(n), self%pt(n), self%stage_q(n, s), &
              self%g_start(ng), self%g_end(ng), self%g_trial(ng), self%grads(n, ng), self%sorted(s), &
              self%order(s), self%g_samples(ng, s), stat=stat)
    if (stat /= 0) then
      stat = VCI_ERR_MEMORY; return
    end if
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
    real(dp), intent(out) :: q_new(:), p_new(:), e_new
    character(len=*), intent(inout) :: cause
    integer, intent(out) :: stat
    real(dp) :: tau, elapsed, alpha, best, mu, e_before
    integer :: j, jbest
    self%max_impacts = max_impacts
    self%a(:) = q; self%pa(:) = p
    tau = h; elapsed = 0.0_dp
    impacts%count = 0
    do
      self%qe(:) = self%a; self%pe(:) = self%pa
      call self%map%flow(self%qe, self%pe, dir * tau, stat, self%stage_q)
      if (stat /= VCI_OK) then
        call fail(self, 'regular step', stat, cause); return
      end if
      if (self%ng == 0) exit
      call gaps(self, self%qe, self%g_end, stat)
      if (stat /= VCI_OK) then
        call fail(self, 'gaps of the step''s end', stat, cause); return
      end if
      self%start_gaps_known = .false.       ! (evaluated only when a wall may be crossed)
      self%samples_known = .false.
      ! stage 1: the first wall reached along the composed map
      best = 2.0_dp; jbest = 0
      do j = 1, self%ng
        call first_crossing(self, j, dir, tau, best, alpha, stat)
        if (stat /= VCI_OK) then
          call fail(self, 'stage 1 (impact time)', stat, cause); return
        end if
        if (alpha < best) then
          best = alpha; jbest = j
        end if
      end do
      if (jbest == 0) exit
      if (impacts%count >= max_impacts) then
        stat = VCI_ERR_TOO_MANY_IMPACTS
        write (cause, '(a,i0,a)') 'more than ', max_impacts, ' impacts in one step (persistent contact or chatter)'
        return
      end if
      ! stage 2: the exact reflection at the wall point of the composed map over best * tau
      self%qt = self%a; self%pt = self%pa
      if (best > 0.0_dp) call self%map%flow(self%qt, self%pt, dir * best * tau, stat)
      if (stat == VCI_OK) call gap_gradients(self, self%qt, stat)
      if (stat == VCI_OK) call self%map%hamiltonian(self%qt, self%pt, e_before, stat)
      if (stat /= VCI_OK) then
        call fail(self, 'stage 2 (reflection)', stat, cause); return
      end if
      call self%map%model%inverse_mass_times(self%grads(:, jbest), self%qe)   ! qe: M⁻¹∇g (scratch)
      mu = dot_product(self%grads(:, jbest), self%qe)
      if (.not. mu > 0.0_dp) then
        stat = VCI_ERR_IMPACT
        write (cause, '(a,i0,a)') 'stage 2: gradient of gap ', jbest, ' vanishes at the impact point'
        return
      end if
      mu = -2.0_dp * dot_product(self%qe, self%pt) / mu
      elapsed = elapsed + best * tau
      call record(self, impacts, dir, h, t, elapsed, jbest, mu, e_before, stat)
      if (stat /= VCI_OK) then
        call fail(self, 'impact record', stat, cause); return
      end if
      self%a = self%qt
      self%pa = self%pt + mu * self%grads(:, jbest)
      tau = h - elapsed
    end do
    q_new(:) = self%qe; p_new(:) = self%pe
    call self%map%hamiltonian(q_new, p_new, e_new, stat)
    if (stat /= VCI_OK) call fail(self, 'energy of the new state', stat, cause)
  end subroutine explicit_advance

  !> Stage 1 for wall j on the sub-step of length tau from (a, pa): alpha = the fraction at which
  !> the composed map first reaches g_j = 0, or 2 when it does not within the sub-step (nor before
  !> `limit`, the earliest wall found so far: a crossing after it does not matter).
  subroutine first_crossing(self, j, dir, tau, limit, alpha, stat)
    type(vci_explicit_t), intent(inout) :: self
    integer, intent(in) :: j, dir
    real(dp), intent(in) :: tau, limit
    real(dp), intent(out) :: alpha
    integer, intent(out) :: stat
    real(dp) :: lo, hi, glo, ghi, c, g, gs
    integer :: i, k, nk, side
    logical :: have_lo, any_inside, on_wall
    alpha = 2.0_dp; stat = VCI_OK
    nk = self%samples
    if (.not. self%samples_known) then      ! every wall's gap at every internal stage, once
      do k = 1, nk - 1
        call gaps(self, self%stage_q(:, self%order(k)), self%g_samples(:, k), stat)
        if (stat /= VCI_OK) return
      end do
      self%samples_known = .true.
    end if
    any_inside = self%g_end(j) < 0.0_dp .or. any(self%g_samples(j, 1:nk - 1) < 0.0_dp)
    if (.not. any_inside) return
    ! A start on the wall (after a reflection, or a step that ended on it), to within the rounding
    ! of g there: moving into it, reflect at once; departing from it, the bracket's low end is the
    ! first point of the true map that is admissible again, and only the end can show a return
    ! (internal stages close to the start scatter around g = 0 by their low-order error).
    if (.not. self%start_gaps_known) then
      call gaps(self, self%a, self%g_start, stat)
      if (stat /= VCI_OK) return
      self%start_gaps_known = .true.
    end if
    call gap_gradients(self, self%a, stat)
    if (stat /= VCI_OK) return
    on_wall = self%g_start(j) <= 64.0_dp * epsilon(1.0_dp) * sum(abs(self%grads(:, j)) * max(abs(self%a), 1.0_dp))
    if (on_wall) then
      call self%map%model%inverse_mass_times(self%pa, self%qt)
      if (dir * dot_product(self%grads(:, j), self%qt) < 0.0_dp) then
        alpha = 0.0_dp; return
      end if
      if (.not. self%g_end(j) < 0.0_dp) return
    end if
    have_lo = .not. on_wall
    lo = 0.0_dp; glo = self%g_start(j)
    hi = -1.0_dp
    do k = 1, nk
      c = self%sorted(k)
      if (c >= limit) return                   ! a wall already found comes first
      if (k < nk .and. have_lo) then
        if (on_wall .or. self%g_samples(j, k) >= 0.0_dp) cycle   ! admissible sample: no need of the true map
      end if
      call gap_on_map(self, j, dir, c * tau, g, stat)
      if (stat /= VCI_OK) return
      if (g > 0.0_dp) then
        have_lo = .true.; lo = c; glo = g
      else if (have_lo) then
        hi = c; ghi = g; exit
      end if
    end do
    if (hi < 0.0_dp) return                    ! never departed or never came back
    if (ghi == 0.0_dp) then
      alpha = hi; return
    end if
    ! Illinois on [lo, hi]: g(lo) > 0 > g(hi)
    side = 0
    do i = 1, ILLINOIS_MAX
      c = (lo * ghi - hi * glo) / (ghi - glo)
      if (.not. (c > lo .and. c < hi)) c = 0.5_dp * (lo + hi)
      if (c <= lo .or. c >= hi) exit          ! no floating-point number left between the ends
      call gap_on_map(self, j, dir, c * tau, gs, stat)
      if (stat /= VCI_OK) return
      if (gs == 0.0_dp) then
        lo = c; glo = gs; exit
      else if (gs > 0.0_dp) then
        lo = c; glo = gs
        if (side == 1) ghi = 0.5_dp * ghi
        side = 1
      else
        hi = c; ghi = gs
        if (side == -1) glo = 0.5_dp * glo
        side = -1
      end if
      if (hi - lo <= 2.0_dp * epsilon(1.0_dp) * hi) exit
    end do
    alpha = lo                                 ! the admissible side of the crossing
  end subroutine first_crossing

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

  subroutine gap_gradients(self, q, stat)
    type(vci_explicit_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    integer, intent(out) :: stat
    integer :: s
    s = 0
    call self%map%model%gap_gradients(q, self%grads(:, 1:self%ng), s)
    call callback_status(self, s, all(abs(self%grads(:, 1:self%ng)) <= huge(1.0_dp)), stat)
  end subroutine gap_gradients

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
  subroutine record(self, impacts, dir, h, t, elapsed, j, mu, e_before, stat)
    type(vci_explicit_t), intent(inout) :: self
    type(vci_impact_buffer_t), intent(inout) :: impacts
    integer, intent(in) :: dir, j
    real(dp), intent(in) :: h, t, elapsed, mu, e_before
    integer, intent(out) :: stat
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
      imp%p_after = self%pt + mu * self%grads(:, j)
      imp%grad_g = self%grads(:, j)
      imp%impulse = real(dir, dp) * mu
      imp%condition = VCI_IMPACT_HAMILTONIAN
      imp%energy_before = e_before
      call self%map%hamiltonian(self%qt, imp%p_after, e_after, stat)
      imp%energy_after = e_after
      call self%map%model%inverse_mass_times(imp%p_after, self%qe)
      imp%leave_rate = real(dir, dp) * dot_product(self%grads(:, j), self%qe)
      imp%stage1_residual = 0.0_dp
      imp%stage2_residual = 0.0_dp
    end associate
  end subroutine record

  subroutine fail(self, what, stat, cause)
    type(vci_explicit_t), intent(in) :: self
    character(len=*), intent(in) :: what
    integer, intent(in) :: stat
    character(len=*), intent(inout) :: cause
    select case (stat)
    case (VCI_ERR_CALLBACK)
      write (cause, '(a,i0,a)') what//': a callback of the model reported failure (stat = ', self%map%failed_stat, ')'
    case (VCI_ERR_NONFINITE)
      cause = what//': a callback of the model returned NaN or Inf'
    case (VCI_ERR_MEMORY)
      cause = what//': out of memory'
    case default
      cause = what//' failed'
    end select
  end subroutine fail
end module vci_explicit_step
