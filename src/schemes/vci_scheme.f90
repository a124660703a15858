!> A scheme: how one sub-step of the (+) or (-) method is discretised and how its unknowns are laid
!> out. The stepper (vci_stepper) runs the algorithm of docs/DESIGN.md §1-2 — regular sub-step, stage 1
!> (reach the wall: adds alpha and g_j = 0), stage 2 (reflect: adds mu and the energy equation) — and
!> asks the scheme for residuals, Jacobians and the quantities it needs (endpoint, multipliers, alpha,
!> mu, outgoing momentum, energy) through the procedures below; it never indexes the unknowns itself.
!>
!> Families: `vci_scheme_discrete` (a user's L_d, and the `left` and `midpoint` retractions of a
!> continuous L, which are discrete Lagrangians in closed form) and `vci_scheme_lobatto` (the Galerkin
!> discrete Lagrangian with s + 1 Lobatto points, whose interior stage values are unknowns of the same
!> Newton system).
!>
!> Contract on layouts: the unknowns of a stage-1 (KIND_STAGE1) or stage-2 (KIND_STAGE2) system are
!> those of the sub-step system followed by one scalar (alpha or mu; `get_extra`/`put_extra`), so a
!> sub-step solution is a valid start for either. KIND_PAIR has the sub-step's layout (it solves for
!> the interior stages of a segment with both ends given). KIND_IMPULSE (the Hamiltonian impact's
!> [nu, mu] system) is scheme-independent and implemented here.
module vci_scheme
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use vci_kinds, only: dp
  use vci_status, only: VCI_OK, VCI_ERR_CALLBACK, VCI_ERR_NONFINITE, VCI_ERR_NEWTON, VCI_ERR_MEMORY
  use vci_lapack, only: dgetrf, dgetrs
  use vci_model_base, only: vci_model_base_t
  use vci_newton, only: vci_system_t, vci_newton_t, vci_newton_result_t
  implicit none
  private

  integer, parameter, public :: KIND_SUBSTEP = 1, KIND_STAGE1 = 2, KIND_STAGE2 = 3, KIND_IMPULSE = 4, &
                                KIND_PAIR = 5
  !> Impact energy conditions (set_impact_energy; the C ABI uses the same numbers).
  integer, parameter, public :: VCI_IMPACT_DISCRETE = 0     !< the paper's E_d(alpha h) = E_d((1 - alpha) h), the default
  integer, parameter, public :: VCI_IMPACT_HAMILTONIAN = 1  !< H(q~, p+) = H(q~, p-), with the model's energy
  !> In impact records only: near a graze the discrete condition blended with H,
  !> w (E_d+ - E_d-) + (1 - w) (H+ - H-) = 0 with a weight symmetric under reversal (docs/BACKWARD.md)
  integer, parameter, public :: VCI_IMPACT_BLENDED = 2

  !> Scheme identifiers (the C ABI uses the same numbers).
  integer, parameter, public :: VCI_SCHEME_DISCRETE = 0  !< the model is a discrete L_d (vci_model_t)
  integer, parameter, public :: VCI_SCHEME_LEFT = 1      !< L_d = h L(q, (v - q)/h), omega_d at q
  integer, parameter, public :: VCI_SCHEME_MIDPOINT = 2  !< L_d = h L((q + v)/2, (v - q)/h), omega_d at the midpoint
  integer, parameter, public :: VCI_SCHEME_LOBATTO = 3   !< Galerkin, s + 1 Lobatto points, order 2s
  !> Störmer–Verlet (order 2) and its symmetric compositions of order 4 .. 10: explicit, for a
  !> separable model (vci_separable_t); `stages` of set_scheme is the order (vci_composition)
  integer, parameter, public :: VCI_SCHEME_COMPOSITION = 4

  type, abstract, extends(vci_system_t), public :: vci_scheme_t
    class(vci_model_base_t), pointer :: base => null()   !< sizes, walls, forms, H
    integer :: n = 0, m = 0, n_gaps = 0
    integer :: kind = KIND_SUBSTEP
    integer :: dir = 1                   !< +1 forward, -1 backward
    real(dp) :: tau = 0.0_dp             !< sub-step length (sub-step, stage 2); alpha * tau is stage 1's
    integer :: gap = 0                   !< wall of stage 1 / stage 2
    integer :: impact_energy = VCI_IMPACT_DISCRETE
    real(dp) :: rtol = 1.0e-12_dp        !< the Newton tolerance, to express the round-off floor in its units
    logical :: has_gap_gradients = .false.
    !> The model's gap_gradient (one wall's gradient, O(n)) answers: used where one wall's is needed
    logical :: has_gap_gradient = .false.
    real(dp), allocatable :: a(:), pa(:), omega(:, :), grad(:), gscale(:)
    real(dp), allocatable :: b_target(:) !< KIND_PAIR: the given end of the segment
    real(dp) :: e_minus = 0.0_dp         !< E_d of the arriving sub-step, or H(qt, p_minus)
    character(len=48) :: failed_callback = ''   !< which callback failed in the last evaluation
    integer :: failed_stat = 0           !< the stat that callback set (> 0 recoverable, < 0 not)
    real(dp), allocatable :: pplus(:)
    !> Stage 2's blended energy row (pose_blend, blended_row; docs/BACKWARD.md, "A reversible energy
    !> condition"): H and the normal kinetic energy of p_minus, and the last row's weight and energies
    real(dp) :: h_minus = 0.0_dp, ke_minus = 0.0_dp
    real(dp) :: blend_w = 1.0_dp, blend_e_before = 0.0_dp, blend_e_after = 0.0_dp
    real(dp) :: blend_delta = 0.0_dp   !< the last row's offset delta, (E_d+ - H+) - (E_d- - H-)
    real(dp), allocatable, private :: all_grads(:, :)   !< every wall's gradient, for eval_gap_gradient's fallback
    real(dp), allocatable, private :: gp(:), gm(:), qp(:), vout(:), xsave(:), ip(:), im(:), isp(:), ism(:)
    real(dp), allocatable, private :: pj_a(:), pj_pa(:), pj_om(:, :), pj_x(:), pj_jac(:, :), pj_rhs(:, :)
    integer, allocatable, private :: pj_ipiv(:)
  contains
    procedure(unknowns_iface), deferred :: unknowns
    procedure(rows_iface), deferred :: scheme_residual
    procedure(jac_iface), deferred :: scheme_jacobian
    procedure(put_endpoint_iface), deferred :: put_endpoint
    procedure(get_endpoint_iface), deferred :: get_endpoint
    procedure(put_vec_iface), deferred :: put_multipliers
    procedure(get_vec_iface), deferred :: get_multipliers
    procedure(momentum_rhs_iface), deferred :: momentum_rhs
    procedure(out_vec_iface), deferred :: momentum_out
    procedure(out_scalar_iface), deferred :: energy_out
    procedure(hamiltonian_iface), deferred :: hamiltonian
    procedure :: pose_substep
    procedure :: pose_stage1
    procedure :: pose_stage2
    procedure :: pose_impulse
    procedure :: pose_blend
    procedure :: blended_row
    procedure :: pose_pair
    procedure :: set_direction
    procedure :: set_wall_normal
    procedure :: configure_impacts
    procedure :: impact_momentum
    procedure :: project_momentum
    procedure :: use_derivatives
    procedure :: clear_failure
    procedure :: position_carry
    procedure :: restore_position_carry
    procedure :: start_memory
    procedure :: restore_start_memory
    procedure :: needs_pair_solve
    procedure :: endpoint_direction
    procedure :: put_quadratic_start
    !> (issue 27) the velocity at the end of a solved sub-step from the scheme's own polynomial
    procedure :: end_velocity
    procedure :: put_multiplier_history
    !> (issue 25) the sub-step's stage polynomial, for the poke screen: its degree (0: none), its
    !> interior stage points and the weights of its Bernstein coefficients
    procedure :: path_degree
    procedure :: path_point
    procedure :: path_bernstein
    procedure :: forget_jacobian
    procedure :: keep_row_sizes, restore_row_sizes
    procedure :: fused_substep => no_fused_substep
    procedure :: substep_sensitivity => no_substep_sensitivity
    procedure :: setup_common
    procedure :: extra_index
    procedure :: get_extra
    procedure :: put_extra
    procedure :: residual => dispatch_residual
    procedure :: jacobian => dispatch_jacobian
    procedure :: admissible => wall_admissible
    procedure :: reuse_key => substep_key
    procedure :: border => stage_border
    procedure :: eval_gaps
    procedure :: eval_gap_gradients
    procedure :: eval_gap_gradient
    procedure :: eval_forms
    procedure :: check
    procedure :: note_failure
    procedure :: check_matrix
    procedure :: check_band
    procedure :: row_name
  end type vci_scheme_t

  abstract interface
    !> Number of unknowns of a system kind.
    pure integer function unknowns_iface(self, kind)
      import :: vci_scheme_t
      class(vci_scheme_t), intent(in) :: self
      integer, intent(in) :: kind
    end function unknowns_iface
    subroutine rows_iface(self, x, r, scale, stat)
      import :: vci_scheme_t, dp
      class(vci_scheme_t), intent(inout) :: self
      real(dp), intent(in) :: x(:)
      real(dp), intent(out) :: r(:), scale(:)
      integer, intent(out) :: stat
    end subroutine rows_iface
    subroutine jac_iface(self, x, r, jac, stat)
      import :: vci_scheme_t, dp
      class(vci_scheme_t), intent(inout) :: self
      real(dp), intent(in) :: x(:), r(:)
      real(dp), intent(inout) :: jac(:, :)
      integer, intent(out) :: stat
    end subroutine jac_iface
    !> Put b as the endpoint of x (interior stage values on the chord from a); other unknowns untouched.
    subroutine put_endpoint_iface(self, x, a, b)
      import :: vci_scheme_t, dp
      class(vci_scheme_t), intent(in) :: self
      real(dp), intent(inout) :: x(:)
      real(dp), intent(in) :: a(:), b(:)
    end subroutine put_endpoint_iface
    subroutine get_vec_iface(self, x, v)
      import :: vci_scheme_t, dp
      class(vci_scheme_t), intent(in) :: self
      real(dp), intent(in) :: x(:)
      real(dp), intent(out) :: v(:)
    end subroutine get_vec_iface
    !> The endpoint of the unknowns x (inout: a scheme may remember the rounding of the last one).
    subroutine get_endpoint_iface(self, x, v)
      import :: vci_scheme_t, dp
      class(vci_scheme_t), intent(inout) :: self
      real(dp), intent(in) :: x(:)
      real(dp), intent(out) :: v(:)
    end subroutine get_endpoint_iface
    subroutine put_vec_iface(self, x, v)
      import :: vci_scheme_t, dp
      class(vci_scheme_t), intent(in) :: self
      real(dp), intent(inout) :: x(:)
      real(dp), intent(in) :: v(:)
    end subroutine put_vec_iface
    !> rhs = a vector of the sub-step's size with v in the momentum rows (those carrying p_a) and 0 elsewhere.
    subroutine momentum_rhs_iface(self, v, rhs)
      import :: vci_scheme_t, dp
      class(vci_scheme_t), intent(in) :: self
      real(dp), intent(in) :: v(:)
      real(dp), intent(out) :: rhs(:)
    end subroutine momentum_rhs_iface
    !> The momentum at the far end of the segment from a of length tau whose unknowns are x.
    !> pa (optional): the momentum at a that x's momentum rows balance, when x solved the sub-step
    !> posed from a (schemes may then use it instead of differencing the segment's kinetic terms).
    subroutine out_vec_iface(self, x, a, tau, p, stat, pa)
      import :: vci_scheme_t, dp
      class(vci_scheme_t), intent(inout) :: self
      real(dp), intent(in) :: x(:), a(:), tau
      real(dp), intent(out) :: p(:)
      integer, intent(out) :: stat
      real(dp), intent(in), optional :: pa(:)
    end subroutine out_vec_iface
    !> The discrete energy E_d = -D3 L_d of that segment.
    subroutine out_scalar_iface(self, x, a, tau, e, stat)
      import :: vci_scheme_t, dp
      class(vci_scheme_t), intent(inout) :: self
      real(dp), intent(in) :: x(:), a(:), tau
      real(dp), intent(out) :: e
      integer, intent(out) :: stat
    end subroutine out_scalar_iface
    !> A step-independent energy H(q, p) (the hamiltonian impact condition).
    subroutine hamiltonian_iface(self, q, p, e, stat)
      import :: vci_scheme_t, dp
      class(vci_scheme_t), intent(inout) :: self
      real(dp), intent(in) :: q(:), p(:)
      real(dp), intent(out) :: e
      integer, intent(out) :: stat
    end subroutine hamiltonian_iface
  end interface

  real(dp), parameter, public :: vci_fd_rel = 6.0e-6_dp   ! ~ eps**(1/3): central differences

contains

  !> Sizes and the workspace every scheme shares (once, before the step loop); stat /= 0: out of memory.
  subroutine setup_common(self, base, stat)
    class(vci_scheme_t), intent(inout) :: self
    class(vci_model_base_t), target, intent(inout) :: base
    integer, intent(out) :: stat
    integer :: n, m, ng
    self%base => base
    n = base%n; m = base%m; ng = max(1, base%n_gaps)
    self%n = n; self%m = m; self%n_gaps = base%n_gaps
    if (allocated(self%a)) deallocate (self%a, self%pa, self%omega, self%grad, self%gscale, self%b_target, &
                                       self%pplus, self%gp, self%gm, self%qp, self%vout, self%xsave, self%ip, &
                                       self%im, self%isp, self%ism)
    allocate (self%a(n), self%pa(n), self%omega(n, m), self%grad(n), self%gscale(n), self%b_target(n), &
              self%pplus(n), self%gp(ng), self%gm(ng), self%qp(n), self%vout(n), self%xsave(m + 1), &
              self%ip(m + 1), self%im(m + 1), self%isp(m + 1), self%ism(m + 1), stat=stat)
    if (stat /= 0) return
    if (allocated(self%pj_a)) deallocate (self%pj_a, self%pj_pa, self%pj_om, self%pj_x, self%pj_jac, self%pj_rhs, &
                                          self%pj_ipiv)
    allocate (self%pj_a(n), self%pj_pa(n), self%pj_om(n, m), self%pj_x(m + 1), self%pj_jac(m, m), &
              self%pj_rhs(m, 1), self%pj_ipiv(m), stat=stat)
    if (stat /= 0) return
    self%omega = 0.0_dp
    self%a = 0.0_dp; self%pa = 0.0_dp; self%grad = 0.0_dp; self%gscale = 0.0_dp
  end subroutine setup_common

  !> The regular sub-step from (a, pa) of length tau (forms Omega(a) evaluated when m > 0).
  subroutine pose_substep(self, a, pa, tau, stat)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(in) :: a(:), pa(:), tau
    integer, intent(out) :: stat
    self%kind = KIND_SUBSTEP
    self%a(:) = a; self%pa(:) = pa; self%tau = tau   ! (:): no reallocation check on the hot path
    stat = VCI_OK
    if (self%m > 0) call self%eval_forms(a, self%omega, stat)
  end subroutine pose_substep

  !> Stage 1 towards wall `gap` (gradient grad_g at a) from (a, pa) over at most tau.
  subroutine pose_stage1(self, a, pa, tau, gap, grad_g, stat)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(in) :: a(:), pa(:), tau, grad_g(:)
    integer, intent(in) :: gap
    integer, intent(out) :: stat
    self%kind = KIND_STAGE1
    self%a = a; self%pa = pa; self%tau = tau; self%gap = gap
    self%gscale = abs(grad_g)
    stat = VCI_OK
    if (self%m > 0) call self%eval_forms(a, self%omega, stat)
  end subroutine pose_stage1

  !> Stage 2 at wall `gap` from (q_wall, p_minus) over tau with the arriving energy e_minus (the wall
  !> normal set by set_wall_normal, the forms by the last pose_substep at q_wall).
  subroutine pose_stage2(self, q_wall, p_minus, tau, gap, e_minus)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(in) :: q_wall(:), p_minus(:), tau, e_minus
    integer, intent(in) :: gap
    self%kind = KIND_STAGE2
    self%a = q_wall; self%pa = p_minus; self%tau = tau; self%gap = gap
    self%e_minus = e_minus
  end subroutine pose_stage2

  !> The blended energy row's side of the arriving motion (after pose_stage2, whose e_minus is E_d
  !> of the arriving sub-step): H(qt, p-) and the normal kinetic energy of p-.
  subroutine pose_blend(self, stat)
    class(vci_scheme_t), intent(inout) :: self
    integer, intent(out) :: stat
    call self%hamiltonian(self%a, self%pa, self%h_minus, stat)
    if (stat == VCI_OK) call normal_kinetic(self, self%pa, self%h_minus, self%ke_minus, stat)
  end subroutine pose_blend

  !> The blended energy row at impulse mu, with e_out = E_d of the leaving sub-step:
  !>   r = w (E_d+ - E_d-) + (1 - w) (H+ - H-),  delta = (E_d+ - H+) - (E_d- - H-),
  !>   w = min(1, min(K-, K+) / (C |delta|))
  !> with K the normal kinetic energy on either side. Reversed, the two sides swap and delta changes
  !> sign: w is the same and the row only changes sign, so both directions solve one equation; it
  !> is the discrete condition where w = 1 and has a root for every K- (H quadratic in p; C = 0.5
  !> keeps soft impacts near the discrete condition: docs/BACKWARD.md). pose_stage2 and pose_blend
  !> first. sc: the size of its terms; the weight and the two sides' blended energies are kept.
  subroutine blended_row(self, e_out, mu, r, sc, stat)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(in) :: e_out, mu
    real(dp), intent(out) :: r, sc
    integer, intent(out) :: stat
    real(dp), parameter :: c_blend = 0.5_dp
    real(dp) :: hp, kp, delta, kmin, w
    r = 0.0_dp; sc = 1.0_dp
    self%pplus = self%pa + mu * self%grad
    call self%hamiltonian(self%a, self%pplus, hp, stat)
    if (stat == VCI_OK) call normal_kinetic(self, self%pplus, hp, kp, stat)
    if (stat /= VCI_OK) return
    delta = (e_out - hp) - (self%e_minus - self%h_minus)
    kmin = max(min(self%ke_minus, kp), 0.0_dp)
    w = 1.0_dp
    if (kmin < c_blend * abs(delta)) w = kmin / (c_blend * abs(delta))
    r = (hp - self%h_minus) + w * delta
    sc = abs(hp) + abs(self%h_minus) + abs(e_out) + abs(self%e_minus)
    self%blend_w = w
    self%blend_delta = delta
    self%blend_e_before = w * self%e_minus + (1.0_dp - w) * self%h_minus
    self%blend_e_after = w * e_out + (1.0_dp - w) * hp
  end subroutine blended_row

  !> The normal kinetic energy of p at a: v_n^2 / (2 k) along the wall normal g, with v_n and k the
  !> first and second derivatives of H(a, p + t g) at t = 0 (central differences over t = eps |p| / |g|,
  !> a function of p alone so that both directions compute the same value; exact for H quadratic in
  !> p, where it is H(p) minus the minimum of H on the line). hp = H(a, p). Where H is not convex
  !> along g the kinetic energy counts as large (w = 1: the discrete condition).
  subroutine normal_kinetic(self, p, hp, ke, stat)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(in) :: p(:), hp
    real(dp), intent(out) :: ke
    integer, intent(out) :: stat
    real(dp) :: t, hplus, hminus, vn, k
    ke = huge(1.0_dp)
    t = 0.1_dp * max(sqrt(sum(p**2)), tiny(1.0_dp)) / max(sqrt(sum(self%grad**2)), tiny(1.0_dp))
    self%qp = p + t * self%grad
    call self%hamiltonian(self%a, self%qp, hplus, stat)
    if (stat /= VCI_OK) return
    self%qp = p - t * self%grad
    call self%hamiltonian(self%a, self%qp, hminus, stat)
    if (stat /= VCI_OK) return
    vn = (hplus - hminus) / (2.0_dp * t)
    k = (hplus - 2.0_dp * hp + hminus) / t**2
    if (k > 0.0_dp) ke = vn**2 / (2.0_dp * k)
  end subroutine normal_kinetic

  !> The Hamiltonian impact's [nu, mu] system at (q_wall, p_minus) with H(q_wall, p_minus) = e_minus.
  subroutine pose_impulse(self, q_wall, p_minus, e_minus)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(in) :: q_wall(:), p_minus(:), e_minus
    self%kind = KIND_IMPULSE
    self%a = q_wall; self%pa = p_minus; self%e_minus = e_minus
  end subroutine pose_impulse

  !> The interior stages of the segment from a to the given b of length tau (the initial pair).
  subroutine pose_pair(self, a, b, tau)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(in) :: a(:), b(:), tau
    self%kind = KIND_PAIR
    self%a = a; self%b_target = b; self%tau = tau
  end subroutine pose_pair

  !> Time direction of the sub-steps posed next: +1 forward, -1 backward.
  subroutine set_direction(self, dir)
    class(vci_scheme_t), intent(inout) :: self
    integer, intent(in) :: dir
    self%dir = dir
  end subroutine set_direction

  !> The gradient of the wall being reflected from (stage 2, the impulse system).
  subroutine set_wall_normal(self, grad_g)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(in) :: grad_g(:)
    self%grad = grad_g
  end subroutine set_wall_normal

  !> The momentum at the end of a sub-step of an impact step (stage 1's arrival, the sub-step that
  !> leaves the wall): momentum_out, unless the scheme has a form with less round-off there.
  subroutine impact_momentum(self, x, a, tau, p, stat, pa)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), a(:), tau
    real(dp), intent(out) :: p(:)
    integer, intent(out) :: stat
    real(dp), intent(in), optional :: pa(:)
    call self%momentum_out(x, a, tau, p, stat, pa)
  end subroutine impact_momentum

  !> p := p + Omega(q) nu with Omega(q)^T dH/dp(q, p) = 0: the momentum's admissible part at q, whose
  !> H is the energy of the motion the constraints allow (the Omega(q)-part of a momentum is no motion:
  !> the next sub-step's multiplier absorbs it). Newton on nu with dH/dp by central differences (the
  !> impulse system's rows at mu = 0; exact for H quadratic in p), to the solver's relative tolerance.
  !> The posed system (a, pa, forms, kind) is left as it was. Nothing to do when m = 0.
  subroutine project_momentum(self, q, p, stat)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(inout) :: p(:)
    integer, intent(out) :: stat
    real(dp) :: d, xj, pscale, acc
    integer :: m, it, j, i, info, kind0
    m = self%m
    stat = VCI_OK
    if (m == 0) return
    associate (a0 => self%pj_a, pa0 => self%pj_pa, om0 => self%pj_om, x => self%pj_x, r => self%ip, &
               sc => self%isp, rp => self%im, rm => self%ism, jac => self%pj_jac, rhs => self%pj_rhs, &
               ipiv => self%pj_ipiv)
    a0 = self%a; pa0 = self%pa; om0 = self%omega; kind0 = self%kind
    self%a = q; self%pa = p; self%kind = KIND_IMPULSE
    call self%eval_forms(q, self%omega, stat)
    x = 0.0_dp
    pscale = max(maxval(abs(p)), tiny(1.0_dp))
    do it = 1, 20
      if (stat /= VCI_OK) exit
      call impulse_rows(self, x, r, sc, stat)
      if (stat /= VCI_OK) exit
      if (all(abs(r(1:m)) <= max(self%rtol, epsilon(1.0_dp)) * sc(1:m))) exit
      if (it == 20) then
        stat = VCI_ERR_NEWTON; self%failed_stat = 0; self%failed_callback = 'momentum projection'; exit
      end if
      do j = 1, m
        xj = x(j)
        d = vci_fd_rel * max(abs(xj), pscale / max(maxval(abs(self%omega(:, j))), tiny(1.0_dp)))
        x(j) = xj + d
        call impulse_rows(self, x, rp, self%xsave, stat)
        if (stat /= VCI_OK) exit
        x(j) = xj - d
        call impulse_rows(self, x, rm, self%xsave, stat)
        if (stat /= VCI_OK) exit
        x(j) = xj
        jac(:, j) = (rp(1:m) - rm(1:m)) / (2.0_dp * d)
      end do
      if (stat /= VCI_OK) exit
      rhs(:, 1) = r(1:m)
      ! differences of huge finite H values overflow: nothing non-finite to LAPACK (fuzz seed 2963)
      if (.not. (all(ieee_is_finite(jac)) .and. all(ieee_is_finite(rhs)))) then
        stat = VCI_ERR_NONFINITE; self%failed_stat = 0; self%failed_callback = 'momentum projection (not finite)'; exit
      end if
      call dgetrf(m, m, jac, m, ipiv, info)
      if (info == 0) call dgetrs('N', m, 1, jac, m, ipiv, rhs, m, info)
      if (info /= 0) then
        stat = VCI_ERR_NEWTON; self%failed_stat = 0; self%failed_callback = 'momentum projection (singular)'; exit
      end if
      x(1:m) = x(1:m) - rhs(:, 1)
    end do
    if (stat == VCI_OK) then
      do i = 1, self%n   ! + matmul(omega, nu) in matmul's order, without its heap temporary
        acc = 0.0_dp
        do j = 1, m
          acc = acc + self%omega(i, j) * x(j)
        end do
        p(i) = p(i) + acc
      end do
    end if
    self%a = a0; self%pa = pa0; self%omega = om0; self%kind = kind0
    end associate
  end subroutine project_momentum

  !> The impact energy condition and Newton's relative tolerance (once per change of settings).
  subroutine configure_impacts(self, impact_energy, rtol)
    class(vci_scheme_t), intent(inout) :: self
    integer, intent(in) :: impact_energy
    real(dp), intent(in) :: rtol
    self%impact_energy = impact_energy
    self%rtol = rtol
  end subroutine configure_impacts

  !> Which optional model derivatives to use: the gap gradients (else differenced); the mixed
  !> Hessian, the discrete constraint's Jacobian and the fused L_d callback of a closed-form L_d
  !> matter only to schemes that have them (they override).
  subroutine use_derivatives(self, mixed_hessian, gap_gradients, constraint_jacobian, fused)
    class(vci_scheme_t), intent(inout) :: self
    logical, intent(in), optional :: mixed_hessian, gap_gradients, constraint_jacobian
    logical, intent(in), optional :: fused   !< the model's ld_fused (vci_model_t)
    if (present(gap_gradients)) self%has_gap_gradients = gap_gradients
  end subroutine use_derivatives

  !> The part of position q that compensated summation carries beyond q's rounding (zero for schemes
  !> that sum positions plainly). Part of a checkpoint: a restart continues bit for bit.
  subroutine position_carry(self, q, lo)
    class(vci_scheme_t), intent(in) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: lo(:)
    lo = 0.0_dp
  end subroutine position_carry

  !> Continue from position q whose carried part is lo (from position_carry).
  subroutine restore_position_carry(self, q, lo)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), lo(:)
  end subroutine restore_position_carry

  !> Newton's start memory beyond the state (a checkpoint carries it: a restart continues bit for
  !> bit): none here (mem of size 0); Lobatto with constraints keeps its last step's polynomials.
  !> stat: VCI_ERR_MEMORY, mem unallocated, when a memory there is cannot be copied.
  subroutine start_memory(self, mem, stat)
    class(vci_scheme_t), intent(in) :: self
    real(dp), allocatable, intent(out) :: mem(:)
    integer, intent(out) :: stat
    allocate (mem(0))   ! (zero size, tiny and fixed: no stat=)
    stat = VCI_OK
  end subroutine start_memory

  !> Start from memory mem (from start_memory of the same scheme and model); one this scheme cannot
  !> have had, or size 0, is none: the next step starts as after an initialisation.
  subroutine restore_start_memory(self, mem)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(in) :: mem(:)
  end subroutine restore_start_memory

  !> Forget which callback failed last (a new solve starts).
  subroutine clear_failure(self)
    class(vci_scheme_t), intent(inout) :: self
    self%failed_callback = ''
    self%failed_stat = 0
  end subroutine clear_failure

  !> Does starting from a pair (q0, q1) need a solve for interior stages? (no, for closed-form L_d)
  pure logical function needs_pair_solve(self)
    class(vci_scheme_t), intent(in) :: self
    needs_pair_solve = .false.
  end function needs_pair_solve

  !> The endpoint's part of a change dx of the unknowns (a sensitivity, e.g. d x / d mu). Layouts
  !> that store the endpoint itself return get_endpoint(dx); those storing an increment override.
  subroutine endpoint_direction(self, x, v)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    real(dp), intent(out) :: v(:)
    call self%get_endpoint(x, v)
  end subroutine endpoint_direction

  !> The velocity (forward time) at the end of the sub-step of length tau whose solution is x, from
  !> the scheme's own polynomial through it (issue 27: Newton's start for the step after an impact or
  !> after init_from_momentum). Schemes without one beyond the chord (the default) leave v as it is
  !> and return known = .false.
  subroutine end_velocity(self, x, tau, v, known)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), tau
    real(dp), intent(inout) :: v(:)
    logical, intent(out) :: known
    known = .false.
  end subroutine end_velocity

  !> Newton's start from the quadratic through the last three points, a + dh (c v + c (c + 1)/2 (v -
  !> v_before)) at the fraction c of the step (dh = dir h; v, v_before the chord velocities of the last
  !> two steps): here the endpoint c = 1 only; schemes with interior stages place those on it too.
  subroutine put_quadratic_start(self, x, a, dh, v, v_before)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(inout) :: x(:)
    real(dp), intent(in) :: a(:), dh, v(:), v_before(:)
    self%qp(:) = a + dh * (2.0_dp * v - v_before)   ! (workspace of n: an automatic array is a malloc)
    call self%put_endpoint(x, a, self%qp)
  end subroutine put_quadratic_start

  !> Newton's start of the multipliers from the last regular steps' (lam, then lam_before and
  !> lam_before2 one and two steps earlier; depth consecutive regular steps of equal length):
  !> extrapolated to the new step, quadratic from depth 3, linear at 2, the last one before.
  !> `work` (m) is workspace. Schemes with multipliers at several nodes override it.
  subroutine put_multiplier_history(self, x, depth, lam, lam_before, lam_before2, work)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(inout) :: x(:)
    integer, intent(in) :: depth
    real(dp), intent(in) :: lam(:), lam_before(:), lam_before2(:)
    real(dp), intent(inout) :: work(:)
    if (depth >= 3) then
      work = 3.0_dp * (lam - lam_before) + lam_before2
      call self%put_multipliers(x, work)
    else if (depth == 2) then
      work = 2.0_dp * lam - lam_before
      call self%put_multipliers(x, work)
    else
      call self%put_multipliers(x, lam)
    end if
  end subroutine put_multiplier_history

  !> A new solve starts (schemes that size rows from the last Jacobian reset that memory here).
  subroutine forget_jacobian(self)
    class(vci_scheme_t), intent(inout) :: self
  end subroutine forget_jacobian

  !> What a scheme carries from one solve to the next beyond the posed system (the discrete
  !> scheme's row sizes from the last Jacobian, which size the next solve's rows before its own
  !> Jacobian), kept before side solves that must leave the run as it was (vci_impacts:
  !> second_root_exists) and put back after them. Nothing here.
  subroutine keep_row_sizes(self)
    class(vci_scheme_t), intent(inout) :: self
  end subroutine keep_row_sizes

  !> Back to the row sizes keep_row_sizes kept.
  subroutine restore_row_sizes(self)
    class(vci_scheme_t), intent(inout) :: self
  end subroutine restore_row_sizes

  !> The posed regular sub-step solved in one fused routine, when the scheme has one for this
  !> system (done true: x solved, res filled); else done false and x untouched: the caller runs
  !> the general Newton path. Schemes without a fused path keep this default.
  subroutine no_fused_substep(self, nw, x, res, done)
    class(vci_scheme_t), intent(inout) :: self
    type(vci_newton_t), intent(inout) :: nw
    real(dp), intent(inout) :: x(:)
    type(vci_newton_result_t), intent(inout) :: res
    logical, intent(out) :: done
    done = .false.
  end subroutine no_fused_substep

  !> Solve J d = rhs with the factors of the last regular sub-step's Newton matrix, when the scheme
  !> kept them from a fused solve of that sub-step (ok true); else ok false and rhs untouched: the
  !> caller evaluates and factorises the Jacobian itself.
  subroutine no_substep_sensitivity(self, rhs, ok)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(inout) :: rhs(:)
    logical, intent(out) :: ok
    ok = .false.
  end subroutine no_substep_sensitivity

  !> Position of alpha (stage 1), mu (stage 2) or mu (impulse system) among the unknowns.
  pure integer function extra_index(self, kind)
    class(vci_scheme_t), intent(in) :: self
    integer, intent(in) :: kind
    if (kind == KIND_IMPULSE) then
      extra_index = self%m + 1
    else
      extra_index = self%unknowns(KIND_SUBSTEP) + 1
    end if
  end function extra_index

  pure real(dp) function get_extra(self, x, kind)
    class(vci_scheme_t), intent(in) :: self
    real(dp), intent(in) :: x(:)
    integer, intent(in) :: kind
    get_extra = x(self%extra_index(kind))
  end function get_extra

  pure subroutine put_extra(self, x, kind, v)
    class(vci_scheme_t), intent(in) :: self
    real(dp), intent(inout) :: x(:)
    integer, intent(in) :: kind
    real(dp), intent(in) :: v
    x(self%extra_index(kind)) = v
  end subroutine put_extra

  subroutine dispatch_residual(self, x, r, scale, stat)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    real(dp), intent(out) :: r(:), scale(:)
    integer, intent(out) :: stat
    if (self%kind == KIND_IMPULSE) then
      call impulse_rows(self, x, r, scale, stat)
    else
      call self%scheme_residual(x, r, scale, stat)
    end if
  end subroutine dispatch_residual

  subroutine dispatch_jacobian(self, x, r, jac, stat)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(in) :: x(:), r(:)
    real(dp), intent(out) :: jac(:, :)
    integer, intent(out) :: stat
    call zero_jacobian(self, jac)
    stat = VCI_OK
    if (self%kind == KIND_IMPULSE) then
      call impulse_jacobian(self, x, jac, stat)
    else
      call self%scheme_jacobian(x, r, jac, stat)
    end if
  end subroutine dispatch_jacobian

  !> Zero the Jacobian before assembly: with a declared band (and no debug check) only the band of
  !> the position block and the dense border, which are all the assembly writes and all the
  !> structured factorisation reads: O(n bw), not O(n^2) (vci_newton zeroes the rest itself before
  !> a dense fallback).
  subroutine zero_jacobian(self, jac)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(out) :: jac(:, :)
    integer :: nb, bw, nx, i, j
    logical :: chk
    call self%structure(nb, bw, chk)
    nx = size(jac, 2)
    if (nb <= 0 .or. nb > nx .or. bw < 0 .or. chk) then
      jac = 0.0_dp; return
    end if
    do j = 1, nb
      do i = max(1, j - bw), min(nb, j + bw)
        jac(i, j) = 0.0_dp
      end do
      jac(nb + 1:nx, j) = 0.0_dp
    end do
    do j = nb + 1, nx
      jac(:, j) = 0.0_dp
    end do
  end subroutine zero_jacobian

  !> Which equation row i of the posed system is, in words (for the message of a failed solve), from
  !> the layout contract above: the sub-step's rows (momentum balance; with interior stages, theirs
  !> too), its m constraint rows last, then stage 1's gap row or stage 2's energy row; the impulse
  !> system is [nu, mu] with the energy row last.
  function row_name(self, i) result(name)
    class(vci_scheme_t), intent(in) :: self
    integer, intent(in) :: i
    character(len=80) :: name
    integer :: nsub
    nsub = self%unknowns(KIND_SUBSTEP)
    if (self%kind == KIND_IMPULSE) then
      name = 'the energy row (H kept across the impact)'
      if (i <= self%m) write (name, '(a,i0)') 'the constraint-impulse row ', i
      return
    end if
    if (i > nsub .and. self%kind == KIND_STAGE1) then
      write (name, '(a,i0,a)') 'the gap row (g_', self%gap, ' = 0 at the wall)'
    else if (i > nsub) then
      name = 'the energy row (the impact''s energy condition)'
    else if (i > nsub - self%m) then
      write (name, '(a,i0)') 'the constraint row ', i - (nsub - self%m)
    else
      name = 'the momentum rows (discrete Euler-Lagrange)'
    end if
  end function row_name

  !> Regular sub-steps of one length and direction share Newton factors (large systems, vci_newton);
  !> the systems of an impact never do.
  real(dp) function substep_key(self)
    class(vci_scheme_t), intent(inout) :: self
    substep_key = 0.0_dp
    if (self%kind == KIND_SUBSTEP) substep_key = real(self%dir, dp) * self%tau
  end function substep_key

  !> Stage 1 and stage 2 are the sub-step system bordered by alpha or mu, their last unknown (the
  !> layout contract above): Newton eliminates it by its Schur complement (vci_bordered).
  integer function stage_border(self)
    class(vci_scheme_t), intent(inout) :: self
    stage_border = 0
    if (self%kind == KIND_STAGE1 .or. self%kind == KIND_STAGE2) stage_border = 1
  end function stage_border

  !> Stage 1 keeps the impact fraction inside (0, 1].
  logical function wall_admissible(self, x)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    wall_admissible = .true.
    if (self%kind == KIND_STAGE1) then
      wall_admissible = x(size(x)) > 0.0_dp .and. x(size(x)) <= 1.0_dp
    end if
  end function wall_admissible

  subroutine eval_gaps(self, q, g, stat)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(out) :: stat
    stat = 0
    call self%base%gaps(q, g, stat)
    call self%check(stat, g, 'gap functions')
  end subroutine eval_gaps

  !> Gradients of all gaps at q (central differences when the model does not supply them; the
  !> difference buffers hold n_gaps values).
  subroutine eval_gap_gradients(self, q, dg, stat)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(out) :: stat
    integer :: i, ng
    real(dp) :: d
    stat = 0
    if (self%has_gap_gradient .and. .not. self%has_gap_gradients) then
      do i = 1, size(dg, 2)                    ! from the model's one-wall gradients
        call self%eval_gap_gradient(q, i, dg(:, i), stat)
        if (stat /= VCI_OK) return
      end do
      return
    end if
    if (self%has_gap_gradients) then
      call self%base%gap_gradients(q, dg, stat)
      call self%check(stat, dg(:, 1), 'gap gradients')
      if (stat == VCI_OK .and. size(dg, 2) > 1) call self%check_matrix(stat, dg, 'gap gradients')
      return
    end if
    ng = size(dg, 2)
    self%qp = q
    do i = 1, self%n
      d = vci_fd_rel * max(abs(q(i)), 1.0_dp)
      self%qp(i) = q(i) + d
      call self%eval_gaps(self%qp, self%gp(1:ng), stat)
      if (stat /= VCI_OK) return
      self%qp(i) = q(i) - d
      call self%eval_gaps(self%qp, self%gm(1:ng), stat)
      if (stat /= VCI_OK) return
      self%qp(i) = q(i)
      dg(i, :) = (self%gp(1:ng) - self%gm(1:ng)) / (2.0_dp * d)
    end do
  end subroutine eval_gap_gradients

  !> dg = the gradient of wall j alone at q: the model's gap_gradient (O(n)) when it answers, else
  !> column j of eval_gap_gradients (every wall's, then O(n n_gaps)).
  subroutine eval_gap_gradient(self, q, j, dg, stat)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    integer, intent(in) :: j
    real(dp), intent(out) :: dg(:)
    integer, intent(out) :: stat
    stat = 0
    if (self%has_gap_gradient) then
      call self%base%gap_gradient(q, j, dg, stat)
      call self%check(stat, dg, 'gap gradient')
      return
    end if
    if (.not. allocated(self%all_grads)) then
      allocate (self%all_grads(self%n, max(1, self%n_gaps)), stat=stat)
      if (stat /= 0) then
        dg = 0.0_dp
        self%failed_stat = 0; self%failed_callback = 'gap gradients (no memory for every wall''s)'
        stat = VCI_ERR_MEMORY; return
      end if
    end if
    call self%eval_gap_gradients(q, self%all_grads(:, 1:self%n_gaps), stat)
    dg = self%all_grads(:, j)
  end subroutine eval_gap_gradient

  subroutine eval_forms(self, q, omega, stat)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: omega(:, :)
    integer, intent(out) :: stat
    stat = 0
    if (self%m == 0) return
    call self%base%constraint_forms(q, omega, stat)
    call self%check_matrix(stat, omega, 'constraint forms')   ! a nonzero stat is VCI_ERR_CALLBACK
  end subroutine eval_forms

  !> The Hamiltonian impact: energy row and, with constraints, the outgoing velocity dH/dp(qt, p+)
  !> annihilated by the constraint forms. x = [nu(m), mu]. dH/dp by central differences: exact for
  !> H quadratic in p.
  subroutine impulse_rows(self, x, r, sc, stat)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    real(dp), intent(out) :: r(:), sc(:)
    integer, intent(out) :: stat
    integer :: m, i, mu
    real(dp) :: hp, hplus, hminus, d, pmax, noise, pi0, acc
    m = self%m
    self%pplus = self%pa + x(m + 1) * self%grad
    if (m > 0) then
      ! + matmul(omega, x(1:m)), summed in matmul's order: its result would be a heap temporary
      do i = 1, self%n
        acc = 0.0_dp
        do mu = 1, m
          acc = acc + self%omega(i, mu) * x(mu)
        end do
        self%pplus(i) = self%pplus(i) + acc
      end do
    end if
    call self%hamiltonian(self%a, self%pplus, hp, stat)
    if (stat /= VCI_OK) return
    r(m + 1) = hp - self%e_minus
    sc(m + 1) = abs(hp) + abs(self%e_minus)
    if (m == 0) return
    pmax = max(maxval(abs(self%pplus)), tiny(1.0_dp))
    d = 1.0e-4_dp * pmax
    do i = 1, self%n
      pi0 = self%pplus(i)
      self%pplus(i) = pi0 + d
      call self%hamiltonian(self%a, self%pplus, hplus, stat)
      if (stat /= VCI_OK) return
      self%pplus(i) = pi0 - d
      call self%hamiltonian(self%a, self%pplus, hminus, stat)
      if (stat /= VCI_OK) return
      self%pplus(i) = pi0
      self%vout(i) = (hplus - hminus) / (2.0_dp * d)      ! outgoing velocity dH/dp
    end do
    noise = 4.0_dp * epsilon(1.0_dp) * abs(hp) / d      ! round-off of the difference quotients
    do mu = 1, m
      r(mu) = dot_product(self%omega(:, mu), self%vout)
      sc(mu) = sum(abs(self%omega(:, mu)) * (abs(self%vout) + noise / max(self%rtol, epsilon(1.0_dp))))
    end do
  end subroutine impulse_rows

  subroutine impulse_jacobian(self, x, jac, stat)
    class(vci_scheme_t), intent(inout) :: self
    real(dp), intent(in) :: x(:)
    real(dp), intent(out) :: jac(:, :)
    integer, intent(out) :: stat
    integer :: j, nx
    real(dp) :: d, xj, pscale
    nx = size(x)
    pscale = max(maxval(abs(self%pa)), tiny(1.0_dp))
    self%xsave(1:nx) = x
    do j = 1, nx
      xj = x(j)
      if (j == nx) then
        d = vci_fd_rel * max(abs(xj), pscale / max(maxval(abs(self%grad)), tiny(1.0_dp)))
      else
        d = vci_fd_rel * max(abs(xj), pscale / max(maxval(abs(self%omega(:, j))), tiny(1.0_dp)))
      end if
      self%xsave(j) = xj + d
      call impulse_rows(self, self%xsave(1:nx), self%ip(1:nx), self%isp(1:nx), stat)
      if (stat /= VCI_OK) return
      self%xsave(j) = xj - d
      call impulse_rows(self, self%xsave(1:nx), self%im(1:nx), self%ism(1:nx), stat)
      if (stat /= VCI_OK) return
      self%xsave(j) = xj
      jac(1:nx, j) = (self%ip(1:nx) - self%im(1:nx)) / (2.0_dp * d)
    end do
  end subroutine impulse_jacobian

  !> Turn a callback's return into a library status: nonzero -> VCI_ERR_CALLBACK (negative:
  !> unrecoverable, Newton must not back off from it), NaN/Inf -> NONFINITE (recoverable).
  subroutine check(self, stat, values, what)
    class(vci_scheme_t), intent(inout) :: self
    integer, intent(inout) :: stat
    real(dp), intent(in) :: values(:)
    character(len=*), intent(in) :: what
    integer :: i
    if (stat /= 0) then
      call self%note_failure(stat, what)
      stat = VCI_ERR_CALLBACK
      return
    end if
    stat = VCI_OK
    if (abs(sum(values)) <= huge(1.0_dp)) return          ! all finite (one test on the sum)
    do i = 1, size(values)
      if (.not. (abs(values(i)) <= huge(1.0_dp))) then   ! NaN or +-Inf
        stat = VCI_ERR_NONFINITE
        self%failed_stat = 0
        self%failed_callback = what
        return
      end if
    end do
  end subroutine check

  !> A callback named `what` set stat = code /= 0: remember it; a negative code is unrecoverable.
  subroutine note_failure(self, code, what)
    class(vci_scheme_t), intent(inout) :: self
    integer, intent(in) :: code
    character(len=*), intent(in) :: what
    self%failed_stat = code
    if (code < 0) self%unrecoverable = .true.
    self%failed_callback = what
  end subroutine note_failure

  !> check() for a square matrix on its band |i - j| <= bw alone (the rest is zero by declaration).
  subroutine check_band(self, stat, values, bw, what)
    class(vci_scheme_t), intent(inout) :: self
    integer, intent(inout) :: stat
    real(dp), intent(in) :: values(:, :)
    integer, intent(in) :: bw
    character(len=*), intent(in) :: what
    integer :: i, j, n
    real(dp) :: acc
    if (stat /= 0) then
      call self%check(stat, values(:, 1), what); return
    end if
    n = size(values, 1)
    acc = 0.0_dp
    do j = 1, size(values, 2)
      do i = max(1, j - bw), min(n, j + bw)
        acc = acc + values(i, j)
      end do
    end do
    stat = VCI_OK
    if (abs(acc) <= huge(1.0_dp)) return
    do j = 1, size(values, 2)
      call self%check(stat, values(max(1, j - bw):min(n, j + bw), j), what)
      if (stat /= VCI_OK) return
    end do
  end subroutine check_band

  !> check() for a matrix, without the temporary a reshape would allocate.
  subroutine check_matrix(self, stat, values, what)
    class(vci_scheme_t), intent(inout) :: self
    integer, intent(inout) :: stat
    real(dp), intent(in) :: values(:, :)
    character(len=*), intent(in) :: what
    integer :: j
    if (stat == 0) then
      if (abs(sum(values)) <= huge(1.0_dp)) then   ! all finite (one test on the sum)
        stat = VCI_OK; return
      end if
    end if
    call self%check(stat, values(:, 1), what)
    do j = 2, size(values, 2)
      if (stat /= VCI_OK) return
      call self%check(stat, values(:, j), what)
    end do
  end subroutine check_matrix

  !> The degree of the polynomial in which a solved sub-step's stage points lie, its path from the
  !> posed start (the point c = 0) to the new point (c = 1); 0: the scheme has no interior stages, so
  !> nothing between the sub-step's ends is known without another solve (the default).
  pure integer function path_degree(self)
    class(vci_scheme_t), intent(in) :: self
    path_degree = 0
  end function path_degree

  !> Stage point k (1 <= k < path_degree) of the sub-step solved in x: its position q and its node
  !> c in [0, 1]. The default (no stages) returns the posed start at c = 0.
  subroutine path_point(self, x, k, q, c)
    class(vci_scheme_t), intent(in) :: self
    real(dp), intent(in) :: x(:)
    integer, intent(in) :: k
    real(dp), intent(out) :: q(:), c
    q = self%a; c = 0.0_dp
  end subroutine path_point

  !> w(k, i), k, i = 0..path_degree: the Bernstein coefficients of the path's polynomial through
  !> values Y_i at its points i = 0 (start), 1 .. path_degree - 1 (path_point), path_degree (end)
  !> are sum_i w(k, i) Y_i. The default (degree 0) has none.
  subroutine path_bernstein(self, w)
    class(vci_scheme_t), intent(in) :: self
    real(dp), intent(out) :: w(0:, 0:)
    w = 0.0_dp
  end subroutine path_bernstein
end module vci_scheme
