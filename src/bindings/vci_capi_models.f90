!> The C models behind `vci_model` handles (part of the C ABI, include/vci.h): the C callback
!> structs as vci.h lays them out, the C signatures of the callbacks, and the two model types that
!> extend the library's bases with C function pointers and a user pointer (c_model_t: a discrete
!> L_d; c_lagrangian_t: a continuous L), dispatched with c_f_procpointer (no internal procedures,
!> hence no trampolines and no executable stack). Every return code passes through the shared
!> callback adapter (vci_callback_adapter): 0 success, > 0 recoverable, < 0 unrecoverable.
!> Internal to the bindings: its entities are public for vci_capi_registry and vci_capi only.
module vci_capi_models
  use, intrinsic :: iso_c_binding
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use vci_kinds, only: dp
  use vci_status
  use vci_model_base, only: vci_model_base_t
  use vci_model, only: vci_model_t
  use vci_lagrangian, only: vci_lagrangian_t
  use vci_separable, only: vci_separable_t
  use vci_callback_adapter, only: vci_callback_record_t
  implicit none
  public

  !> Mirror of `struct vci_callbacks` in vci.h: a leading size, then the callbacks. New members are
  !> added at the end only; a caller built against an older header passes a smaller size and the
  !> members beyond it are NULL (docs/C_API.md, "Adding a callback").
  type, bind(C) :: vci_callbacks_c
    integer(c_size_t) :: size = 0
    type(c_funptr) :: d1_ld = c_null_funptr, d2_ld = c_null_funptr, d3_ld = c_null_funptr
    type(c_funptr) :: mixed_hessian = c_null_funptr, constraint_forms = c_null_funptr
    type(c_funptr) :: discrete_constraint = c_null_funptr, gaps = c_null_funptr
    type(c_funptr) :: gap_gradients = c_null_funptr, energy = c_null_funptr
    type(c_funptr) :: discrete_constraint_jacobian = c_null_funptr   !< added after 0.2.0 (at the end)
    type(c_funptr) :: ld_fused = c_null_funptr   !< added in issue 26 (at the end)
  end type vci_callbacks_c

  !> The callbacks as vci.h 0.1.0 laid them out (nine pointers, no size): what binaries built
  !> against 0.1 pass to the symbol vci_model_create.
  type, bind(C) :: vci_callbacks_v0_1
    type(c_funptr) :: d1_ld, d2_ld, d3_ld, mixed_hessian, constraint_forms, discrete_constraint, &
                      gaps, gap_gradients, energy
  end type vci_callbacks_v0_1

  !> Mirror of `struct vci_lagrangian_callbacks` in vci.h (continuous models): a leading size of
  !> its own, then the callbacks; the same growth rules as vci_callbacks_c.
  type, bind(C) :: vci_lagrangian_callbacks_c
    integer(c_size_t) :: size = 0
    type(c_funptr) :: lagrangian = c_null_funptr, dl_dq = c_null_funptr, dl_dv = c_null_funptr
    type(c_funptr) :: hessians = c_null_funptr, constraint_forms = c_null_funptr
    type(c_funptr) :: gaps = c_null_funptr, gap_gradients = c_null_funptr, energy = c_null_funptr
    type(c_funptr) :: hessians_band = c_null_funptr   !< added after 0.2 (at the end)
    type(c_funptr) :: hessians_sparse = c_null_funptr !< added in issue 28 (at the end)
  end type vci_lagrangian_callbacks_c

  !> Mirror of `struct vci_separable_callbacks` in vci.h (separable models: constant M, V(q)):
  !> a leading size of its own, then the callbacks; the same growth rules as vci_callbacks_c.
  type, bind(C) :: vci_separable_callbacks_c
    integer(c_size_t) :: size = 0
    type(c_funptr) :: potential = c_null_funptr, potential_gradient = c_null_funptr
    type(c_funptr) :: potential_hessian = c_null_funptr
    type(c_funptr) :: gaps = c_null_funptr, gap_gradients = c_null_funptr
  end type vci_separable_callbacks_c

  !> The C signatures of the callbacks (vci.h); each returns 0, > 0 (recoverable) or < 0.
  !> (L, dL/dq and dL/dqdot have c_energy_fn's shape: n, q, v, out, user.)
  abstract interface
    !> f(n, q, out, user): V(q) (out[1]), ∇V(q) (out[n]) or ∇²V(q) (out[n*n]).
    integer(c_int) function c_q_fn(n, q, out, user) bind(C)
      import :: c_int, c_double, c_ptr
      integer(c_int), value :: n
      real(c_double), intent(in) :: q(*)
      real(c_double), intent(inout) :: out(*)
      type(c_ptr), value :: user
    end function c_q_fn
    integer(c_int) function c_lhess_fn(n, q, v, lqq, lqv, lvv, user) bind(C)
      import :: c_int, c_double, c_ptr
      integer(c_int), value :: n
      real(c_double), intent(in) :: q(*), v(*)
      real(c_double), intent(inout) :: lqq(*), lqv(*), lvv(*)
      type(c_ptr), value :: user
    end function c_lhess_fn
    !> f(n, bw, q, v, lqq, lqv, lvv, user): the Hessian blocks in band storage, each (2 bw + 1) x n.
    integer(c_int) function c_lhess_band_fn(n, bw, q, v, lqq, lqv, lvv, user) bind(C)
      import :: c_int, c_double, c_ptr
      integer(c_int), value :: n, bw
      real(c_double), intent(in) :: q(*), v(*)
      real(c_double), intent(inout) :: lqq(*), lqv(*), lvv(*)
      type(c_ptr), value :: user
    end function c_lhess_band_fn
    !> f(n, nnz, q, v, lqq, lqv, lvv, user): the Hessian blocks in the declared pattern's order.
    integer(c_int) function c_lhess_sparse_fn(n, nnz, q, v, lqq, lqv, lvv, user) bind(C)
      import :: c_int, c_double, c_ptr
      integer(c_int), value :: n, nnz
      real(c_double), intent(in) :: q(*), v(*)
      real(c_double), intent(inout) :: lqq(*), lqv(*), lvv(*)
      type(c_ptr), value :: user
    end function c_lhess_sparse_fn
    integer(c_int) function c_ld_grad_fn(n, q, v, h, out, user) bind(C)
      import :: c_int, c_double, c_ptr
      integer(c_int), value :: n
      real(c_double), intent(in) :: q(*), v(*)
      real(c_double), value :: h
      real(c_double), intent(inout) :: out(*)
      type(c_ptr), value :: user
    end function c_ld_grad_fn
    integer(c_int) function c_ld_fused_fn(n, q, v, h, d1, d2, d3, hess, user) bind(C)
      import :: c_int, c_double, c_ptr
      integer(c_int), value :: n
      real(c_double), intent(in) :: q(*), v(*)
      real(c_double), value :: h
      real(c_double), intent(inout) :: d1(*), d2(*), d3(*), hess(*)
      type(c_ptr), value :: user
    end function c_ld_fused_fn
    integer(c_int) function c_forms_fn(n, m, q, omega, user) bind(C)
      import :: c_int, c_double, c_ptr
      integer(c_int), value :: n, m
      real(c_double), intent(in) :: q(*)
      real(c_double), intent(inout) :: omega(*)
      type(c_ptr), value :: user
    end function c_forms_fn
    integer(c_int) function c_dconstraint_fn(n, m, base, other, h, out, user) bind(C)
      import :: c_int, c_double, c_ptr
      integer(c_int), value :: n, m
      real(c_double), intent(in) :: base(*), other(*)
      real(c_double), value :: h
      real(c_double), intent(inout) :: out(*)
      type(c_ptr), value :: user
    end function c_dconstraint_fn
    integer(c_int) function c_energy_fn(n, q, p, e, user) bind(C)
      import :: c_int, c_double, c_ptr
      integer(c_int), value :: n
      real(c_double), intent(in) :: q(*), p(*)
      real(c_double), intent(inout) :: e(*)
      type(c_ptr), value :: user
    end function c_energy_fn
    integer(c_int) function c_impact_fn(t, alpha, gap_index, q, impulse, user) bind(C)
      import :: c_int, c_double, c_ptr
      real(c_double), value :: t, alpha
      integer(c_int), value :: gap_index
      real(c_double), intent(in) :: q(*)
      real(c_double), value :: impulse
      type(c_ptr), value :: user
    end function c_impact_fn
  end interface

  !> The model behind a `vci_model` handle (immutable once created), and each integrator's own
  !> copy of it: C function pointers, user pointer, and the integrator's callback record.
  !> A continuous model's handle is a c_model_t too (continuous = .true., callbacks in lcb): the
  !> registry, copies and destroy are the same; an integrator made from it drives a c_lagrangian_t.
  type, extends(vci_model_t) :: c_model_t
    type(vci_callbacks_c) :: cb
    logical :: continuous = .false.
    type(vci_lagrangian_callbacks_c) :: lcb
    !> A separable model's handle (continuous too): its callbacks and M (mass_dense: n x n
    !> column-major, else the diagonal), checked symmetric positive definite at creation.
    logical :: separable = .false., mass_dense = .false.
    type(vci_separable_callbacks_c) :: scb
    real(dp), allocatable :: mass(:)
    type(c_ptr) :: user = c_null_ptr
    type(vci_callback_record_t) :: record
  contains
    procedure :: d1 => cm_d1
    procedure :: d2 => cm_d2
    procedure :: d3 => cm_d3
    procedure :: mixed_hessian => cm_hessian
    procedure :: constraint_forms => cm_forms
    procedure :: discrete_constraint => cm_dconstraint
    procedure :: discrete_constraint_jacobian => cm_dconstraint_jacobian
    procedure :: ld_fused => cm_ld_fused
    procedure :: gaps => cm_gaps
    procedure :: gap_gradients => cm_gap_grads
    procedure :: energy => cm_energy
  end type c_model_t

  !> The C continuous model: extends vci_lagrangian_t as c_model_t extends vci_model_t; the return
  !> codes go through the same adapter, into the record of its integrator's model copy.
  type, extends(vci_lagrangian_t) :: c_lagrangian_t
    type(vci_lagrangian_callbacks_c) :: cb
    type(c_ptr) :: user = c_null_ptr
    type(vci_callback_record_t), pointer :: record => null()  !< its integrator's model copy's record, or
    !> the model's own when `record` is not associated (an ensemble member: vci_capi_ensemble)
    type(vci_callback_record_t) :: own_record
  contains
    procedure :: lagrangian => cl_value
    procedure :: dl_dq => cl_dl_dq
    procedure :: dl_dv => cl_dl_dv
    procedure :: hessians => cl_hessians
    procedure :: hessians_band => cl_hessians_band
    procedure :: hessians_sparse => cl_hessians_sparse
    procedure :: constraint_forms => cl_forms
    procedure :: gaps => cl_gaps
    procedure :: gap_gradients => cl_gap_grads
    procedure :: energy => cl_energy
  end type c_lagrangian_t

  !> The C separable model (vci_model_create_separable): extends vci_separable_t with the C
  !> function pointers of V, ∇V, ∇²V and the walls; L, its derivatives and H are derived from M
  !> and V by vci_separable, so every scheme runs it, the explicit compositions included.
  type, extends(vci_separable_t) :: c_separable_t
    type(vci_separable_callbacks_c) :: cb
    type(c_ptr) :: user = c_null_ptr
    type(vci_callback_record_t), pointer :: record => null()
  contains
    procedure :: potential => cs_potential
    procedure :: potential_gradient => cs_gradient
    procedure :: potential_hessian => cs_hessian
    procedure :: gaps => cs_gaps
    procedure :: gap_gradients => cs_gap_grads
  end type c_separable_t

contains

  ! ---------------------------------------------------------------------------------------------
  ! the C models: each procedure calls its C function and hands the return code to the adapter

  logical function finite1(a)
    real(dp), intent(in) :: a(:)
    finite1 = all(ieee_is_finite(a))
  end function finite1

  ! The discrete and the continuous C model share one caller per C function shape: out (nout values)
  ! is zeroed (defined even where a failing callback leaves it unwritten), a NULL callback is "not
  ! provided", else the return code and the finiteness of out go to the model's callback record.

  !> Where a C model (either kind) notes its callbacks' returns, and its user pointer.
  subroutine c_context(model, record, user)
    class(vci_model_base_t), target, intent(inout) :: model
    type(vci_callback_record_t), pointer, intent(out) :: record
    type(c_ptr), intent(out) :: user
    record => null(); user = c_null_ptr
    select type (model)
    type is (c_model_t)
      record => model%record; user = model%user
    type is (c_lagrangian_t)
      record => model%own_record
      if (associated(model%record)) record => model%record
      user = model%user
    class is (c_separable_t)
      record => model%record; user = model%user
    end select
  end subroutine c_context

  !> f(n, q, v, h, out, user): c_ld_grad_fn's shape (D1, D2, D3 L_d, the mixed Hessian).
  subroutine call_qvh(model, fp, name, q, v, h, out, nout, stat)
    class(vci_model_base_t), target, intent(inout) :: model
    type(c_funptr), intent(in) :: fp
    character(len=*), intent(in) :: name
    real(dp), intent(in) :: q(:), v(:), h
    integer, intent(in) :: nout
    real(dp), intent(out) :: out(nout)
    integer, intent(inout) :: stat
    procedure(c_ld_grad_fn), pointer :: f
    type(vci_callback_record_t), pointer :: record
    type(c_ptr) :: user
    integer :: rc
    out = 0.0_dp
    if (.not. c_associated(fp)) then
      call model%not_provided(stat); return
    end if
    call c_context(model, record, user)
    call c_f_procpointer(fp, f)
    rc = f(model%n, q, v, h, out, user)
    call record%note(rc, 'the C callback '//name, finite1(out), stat)
  end subroutine call_qvh

  !> f(n, k, q, out, user): c_forms_fn's shape (constraint forms with k = m; gaps and their
  !> gradients with k = ngaps).
  subroutine call_qk(model, fp, name, k, q, out, nout, stat)
    class(vci_model_base_t), target, intent(inout) :: model
    type(c_funptr), intent(in) :: fp
    character(len=*), intent(in) :: name
    integer, intent(in) :: k, nout
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: out(nout)
    integer, intent(inout) :: stat
    procedure(c_forms_fn), pointer :: f
    type(vci_callback_record_t), pointer :: record
    type(c_ptr) :: user
    integer :: rc
    out = 0.0_dp
    if (.not. c_associated(fp)) then
      call model%not_provided(stat); return
    end if
    call c_context(model, record, user)
    call c_f_procpointer(fp, f)
    rc = f(model%n, k, q, out, user)
    call record%note(rc, 'the C callback '//name, finite1(out), stat)
  end subroutine call_qk

  !> f(n, q, v, out, user): c_energy_fn's shape (L, dL/dq, dL/dqdot; H with v = p).
  subroutine call_qv(model, fp, name, q, v, out, nout, stat)
    class(vci_model_base_t), target, intent(inout) :: model
    type(c_funptr), intent(in) :: fp
    character(len=*), intent(in) :: name
    real(dp), intent(in) :: q(:), v(:)
    integer, intent(in) :: nout
    real(dp), intent(out) :: out(nout)
    integer, intent(inout) :: stat
    procedure(c_energy_fn), pointer :: f
    type(vci_callback_record_t), pointer :: record
    type(c_ptr) :: user
    integer :: rc
    out = 0.0_dp
    if (.not. c_associated(fp)) then
      call model%not_provided(stat); return
    end if
    call c_context(model, record, user)
    call c_f_procpointer(fp, f)
    rc = f(model%n, q, v, out, user)
    call record%note(rc, 'the C callback '//name, finite1(out), stat)
  end subroutine call_qv

  ! ---------------------------------------------------------------------------------------------
  ! the C model (discrete L_d)

  subroutine cm_d1(self, q, v, h, out, stat)
    class(c_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    call call_qvh(self, self%cb%d1_ld, 'd1_ld', q, v, h, out, size(out), stat)
  end subroutine cm_d1

  subroutine cm_d2(self, q, v, h, out, stat)
    class(c_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    call call_qvh(self, self%cb%d2_ld, 'd2_ld', q, v, h, out, size(out), stat)
  end subroutine cm_d2

  subroutine cm_d3(self, q, v, h, out, stat)
    class(c_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out
    integer, intent(inout) :: stat
    real(dp) :: tmp(1)
    call call_qvh(self, self%cb%d3_ld, 'd3_ld', q, v, h, tmp, 1, stat)
    out = tmp(1)
  end subroutine cm_d3

  subroutine cm_hessian(self, q, v, h, hess, stat)
    class(c_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: hess(:, :)
    integer, intent(inout) :: stat
    call call_qvh(self, self%cb%mixed_hessian, 'mixed_hessian', q, v, h, hess, size(hess), stat)
  end subroutine cm_hessian

  subroutine cm_ld_fused(self, q, v, h, d1, d2, d3, hess, stat)
    class(c_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: d1(:), d2(:), d3, hess(:, :)
    integer, intent(inout) :: stat
    call call_fused(self, q, v, h, d1, d2, d3, hess, self%n, stat)
  end subroutine cm_ld_fused

  !> The fused L_d callback (explicit shapes: no temporaries); outputs zeroed first, NULL is "not
  !> provided", the return code and the finiteness of all four outputs go to the callback record.
  subroutine call_fused(self, q, v, h, d1, d2, d3, hess, n, stat)
    class(c_model_t), intent(inout) :: self
    integer, intent(in) :: n
    real(dp), intent(in) :: q(n), v(n), h
    real(dp), intent(out) :: d1(n), d2(n), d3, hess(n * n)
    integer, intent(inout) :: stat
    procedure(c_ld_fused_fn), pointer :: f
    real(dp) :: e(1)
    integer :: rc
    d1 = 0.0_dp; d2 = 0.0_dp; d3 = 0.0_dp; hess = 0.0_dp
    if (.not. c_associated(self%cb%ld_fused)) then
      call self%not_provided(stat); return
    end if
    call c_f_procpointer(self%cb%ld_fused, f)
    e(1) = 0.0_dp
    rc = f(n, q, v, h, d1, d2, e, hess, self%user)
    d3 = e(1)
    call self%record%note(rc, 'the C callback ld_fused', &
                          finite1(d1) .and. finite1(d2) .and. finite1(e) .and. finite1(hess), stat)
  end subroutine call_fused

  subroutine cm_forms(self, q, omega, stat)
    class(c_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: omega(:, :)
    integer, intent(inout) :: stat
    call call_qk(self, self%cb%constraint_forms, 'constraint_forms', self%m, q, omega, size(omega), stat)
  end subroutine cm_forms

  subroutine cm_dconstraint(self, base, other, h, out, stat)
    class(c_model_t), intent(inout) :: self
    real(dp), intent(in) :: base(:), other(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    call call_pair(self, self%cb%discrete_constraint, 'discrete_constraint', base, other, h, out, size(out), stat)
  end subroutine cm_dconstraint

  subroutine cm_dconstraint_jacobian(self, base, other, h, jac, stat)
    class(c_model_t), intent(inout) :: self
    real(dp), intent(in) :: base(:), other(:), h
    real(dp), intent(out) :: jac(:, :)
    integer, intent(inout) :: stat
    call call_pair(self, self%cb%discrete_constraint_jacobian, 'discrete_constraint_jacobian', base, other, h, &
                   jac, size(jac), stat)
  end subroutine cm_dconstraint_jacobian

  !> A C function of the discrete constraint's shape, f(n, m, base, other, h, out, user), with nout
  !> outputs (m: the constraint; m * n: its Jacobian, column-major); "not provided" when NULL.
  subroutine call_pair(model, fp, name, base, other, h, out, nout, stat)
    class(c_model_t), intent(inout) :: model
    type(c_funptr), intent(in) :: fp
    character(len=*), intent(in) :: name
    real(dp), intent(in) :: base(:), other(:), h
    integer, intent(in) :: nout
    real(dp), intent(out) :: out(nout)
    integer, intent(inout) :: stat
    procedure(c_dconstraint_fn), pointer :: f
    integer :: rc
    if (.not. c_associated(fp)) then
      out = 0.0_dp; call model%not_provided(stat); return
    end if
    call c_f_procpointer(fp, f)
    out = 0.0_dp   ! defined even where a failing callback left it unwritten
    rc = f(model%n, model%m, base, other, h, out, model%user)
    call model%record%note(rc, 'the C callback '//name, finite1(out), stat)
  end subroutine call_pair

  subroutine cm_gaps(self, q, g, stat)
    class(c_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    call call_qk(self, self%cb%gaps, 'gaps', self%n_gaps, q, g, size(g), stat)
  end subroutine cm_gaps

  subroutine cm_gap_grads(self, q, dg, stat)
    class(c_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    call call_qk(self, self%cb%gap_gradients, 'gap_gradients', self%n_gaps, q, dg, size(dg), stat)
  end subroutine cm_gap_grads

  subroutine cm_energy(self, q, p, e, stat)
    class(c_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    real(dp) :: tmp(1)
    call call_qv(self, self%cb%energy, 'energy', q, p, tmp, 1, stat)
    e = tmp(1)
  end subroutine cm_energy

  ! ---------------------------------------------------------------------------------------------
  ! the C continuous model: the same callers, with vci_lagrangian_t's procedures

  subroutine cl_value(self, q, v, l, stat)
    class(c_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: l
    integer, intent(inout) :: stat
    real(dp) :: tmp(1)
    call call_qv(self, self%cb%lagrangian, 'lagrangian', q, v, tmp, 1, stat)
    l = tmp(1)
  end subroutine cl_value

  subroutine cl_dl_dq(self, q, v, out, stat)
    class(c_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    call call_qv(self, self%cb%dl_dq, 'dl_dq', q, v, out, size(out), stat)
  end subroutine cl_dl_dq

  subroutine cl_dl_dv(self, q, v, out, stat)
    class(c_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    call call_qv(self, self%cb%dl_dv, 'dl_dv', q, v, out, size(out), stat)
  end subroutine cl_dl_dv

  subroutine cl_hessians(self, q, v, lqq, lqv, lvv, stat)
    class(c_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: lqq(:, :), lqv(:, :), lvv(:, :)
    integer, intent(inout) :: stat
    procedure(c_lhess_fn), pointer :: f
    type(vci_callback_record_t), pointer :: record
    type(c_ptr) :: user
    integer :: rc
    lqq = 0.0_dp; lqv = 0.0_dp; lvv = 0.0_dp   ! defined even where a failing callback left them unwritten
    if (.not. c_associated(self%cb%hessians)) then
      call self%not_provided(stat); return
    end if
    call c_context(self, record, user)
    call c_f_procpointer(self%cb%hessians, f)
    rc = f(self%n, q, v, lqq, lqv, lvv, user)
    call record%note(rc, 'the C callback hessians', all(ieee_is_finite(lqq)) .and. &
                          all(ieee_is_finite(lqv)) .and. all(ieee_is_finite(lvv)), stat)
  end subroutine cl_hessians

  !> The banded blocks ((2 bw + 1) x n each, band storage) from the C callback hessians_band.
  subroutine cl_hessians_band(self, q, v, bw, lqq, lqv, lvv, stat)
    class(c_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    integer, intent(in) :: bw
    real(dp), intent(out) :: lqq(:, :), lqv(:, :), lvv(:, :)
    integer, intent(inout) :: stat
    procedure(c_lhess_band_fn), pointer :: f
    type(vci_callback_record_t), pointer :: record
    type(c_ptr) :: user
    integer :: rc
    lqq = 0.0_dp; lqv = 0.0_dp; lvv = 0.0_dp   ! defined even where a failing callback left them unwritten
    if (.not. c_associated(self%cb%hessians_band)) then
      call self%not_provided(stat); return
    end if
    call c_context(self, record, user)
    call c_f_procpointer(self%cb%hessians_band, f)
    rc = f(self%n, bw, q, v, lqq, lqv, lvv, user)
    call record%note(rc, 'the C callback hessians_band', all(ieee_is_finite(lqq)) .and. &
                          all(ieee_is_finite(lqv)) .and. all(ieee_is_finite(lvv)), stat)
  end subroutine cl_hessians_band

  !> The blocks in the declared sparse pattern (declared order) from the C callback hessians_sparse.
  subroutine cl_hessians_sparse(self, q, v, lqq, lqv, lvv, stat)
    class(c_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: lqq(:), lqv(:), lvv(:)
    integer, intent(inout) :: stat
    procedure(c_lhess_sparse_fn), pointer :: f
    type(vci_callback_record_t), pointer :: record
    type(c_ptr) :: user
    integer :: rc
    lqq = 0.0_dp; lqv = 0.0_dp; lvv = 0.0_dp   ! defined even where a failing callback left them unwritten
    if (.not. c_associated(self%cb%hessians_sparse)) then
      call self%not_provided(stat); return
    end if
    call c_context(self, record, user)
    call c_f_procpointer(self%cb%hessians_sparse, f)
    rc = f(self%n, size(lqq), q, v, lqq, lqv, lvv, user)
    call record%note(rc, 'the C callback hessians_sparse', all(ieee_is_finite(lqq)) .and. &
                          all(ieee_is_finite(lqv)) .and. all(ieee_is_finite(lvv)), stat)
  end subroutine cl_hessians_sparse

  subroutine cl_forms(self, q, omega, stat)
    class(c_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: omega(:, :)
    integer, intent(inout) :: stat
    call call_qk(self, self%cb%constraint_forms, 'constraint_forms', self%m, q, omega, size(omega), stat)
  end subroutine cl_forms

  subroutine cl_gaps(self, q, g, stat)
    class(c_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    call call_qk(self, self%cb%gaps, 'gaps', self%n_gaps, q, g, size(g), stat)
  end subroutine cl_gaps

  subroutine cl_gap_grads(self, q, dg, stat)
    class(c_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    call call_qk(self, self%cb%gap_gradients, 'gap_gradients', self%n_gaps, q, dg, size(dg), stat)
  end subroutine cl_gap_grads

  subroutine cl_energy(self, q, p, e, stat)
    class(c_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    real(dp) :: tmp(1)
    call call_qv(self, self%cb%energy, 'energy', q, p, tmp, 1, stat)
    e = tmp(1)
  end subroutine cl_energy

  ! ---------------------------------------------------------------------------------------------
  ! the C separable model: V, ∇V, ∇²V through f(n, q, out, user); the walls as the others

  !> f(n, q, out, user) with nout outputs; "not provided" when NULL.
  subroutine call_q(model, fp, name, q, out, nout, stat)
    class(c_separable_t), intent(inout) :: model
    type(c_funptr), intent(in) :: fp
    character(len=*), intent(in) :: name
    real(dp), intent(in) :: q(:)
    integer, intent(in) :: nout
    real(dp), intent(out) :: out(nout)
    integer, intent(inout) :: stat
    procedure(c_q_fn), pointer :: f
    integer :: rc
    out = 0.0_dp   ! defined even where a failing callback left it unwritten
    if (.not. c_associated(fp)) then
      call model%not_provided(stat); return
    end if
    call c_f_procpointer(fp, f)
    rc = f(model%n, q, out, model%user)
    call model%record%note(rc, 'the C callback '//name, finite1(out), stat)
  end subroutine call_q

  subroutine cs_potential(self, q, v, stat)
    class(c_separable_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: v
    integer, intent(inout) :: stat
    real(dp) :: tmp(1)
    call call_q(self, self%cb%potential, 'potential', q, tmp, 1, stat)
    v = tmp(1)
  end subroutine cs_potential

  subroutine cs_gradient(self, q, dv, stat)
    class(c_separable_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dv(:)
    integer, intent(inout) :: stat
    call call_q(self, self%cb%potential_gradient, 'potential_gradient', q, dv, size(dv), stat)
  end subroutine cs_gradient

  subroutine cs_hessian(self, q, hv, stat)
    class(c_separable_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: hv(:, :)
    integer, intent(inout) :: stat
    call call_q(self, self%cb%potential_hessian, 'potential_hessian', q, hv, size(hv), stat)
  end subroutine cs_hessian

  subroutine cs_gaps(self, q, g, stat)
    class(c_separable_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    call call_qk(self, self%cb%gaps, 'gaps', self%n_gaps, q, g, size(g), stat)
  end subroutine cs_gaps

  subroutine cs_gap_grads(self, q, dg, stat)
    class(c_separable_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    call call_qk(self, self%cb%gap_gradients, 'gap_gradients', self%n_gaps, q, dg, size(dg), stat)
  end subroutine cs_gap_grads

  !> Bind sep to the handle's model mc (sizes, callbacks, user pointer, record, M): what an
  !> integrator or the model checker drives. stat: VCI_OK, or VCI_ERR_ARGUMENT / VCI_ERR_MEMORY
  !> from set_mass_* (M not symmetric positive definite, not finite).
  subroutine bind_separable(sep, mc, stat)
    type(c_separable_t), intent(inout) :: sep
    type(c_model_t), target, intent(inout) :: mc
    integer, intent(out) :: stat
    sep%n = mc%n; sep%m = mc%m; sep%n_gaps = mc%n_gaps
    sep%cb = mc%scb; sep%user = mc%user; sep%record => mc%record
    if (mc%mass_dense) then
      call sep%set_mass_matrix(reshape(mc%mass, [mc%n, mc%n]), stat)
    else
      call sep%set_mass_diagonal(mc%mass, stat)
    end if
  end subroutine bind_separable

end module vci_capi_models
