!> The C ABI of vci (include/vci.h): the only module that speaks iso_c_binding for C callers.
!>
!> Handles are not addresses: a handle is a token (serial number, slot) into a registry of live
!> objects. Serial numbers are never reused, so NULL, destroyed, foreign or garbage handles give
!> VCI_ERR_ARGUMENT instead of a crash even after malloc has reused the memory of a destroyed object.
!> The registry is guarded by a lock (src/bindings/vci_capi_sync.c), so handles may be created, used and
!> destroyed from any thread.
!>
!> No mutable state is shared between integrators: a model is immutable once created, and each
!> integrator keeps its own copy of it (callbacks, user pointer, sizes) together with its own
!> status, message and callback record. An integrator is marked busy while a call on it runs;
!> another call on it (from a callback it is running, or from another thread) gives VCI_ERR_STATE,
!> and vci_integrator_destroy of a busy integrator is carried out when the running call returns.
!> Failures without a live integrator to hold them (bad handles, failed creation) go to a message
!> of the calling thread, read with vci_last_error(NULL, ...). HDF5 is not thread-safe: all output
!> calls are serialised by a second lock.
!>
!> The C model is one more extension of vci_model_t: it holds the C function pointers and the
!> user pointer and dispatches with c_f_procpointer (no internal procedures, hence no trampolines
!> and no executable stack). Return codes pass through the shared callback adapter
!> (vci_callback_adapter): 0 success, > 0 recoverable, < 0 unrecoverable.
module vci_capi
  use, intrinsic :: iso_c_binding
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use vci_kinds, only: dp, i8
  use vci_status
  use vci_limits, only: vci_size_problem
  use vci_model_base, only: vci_model_base_t
  use vci_model, only: vci_model_t
  use vci_lagrangian, only: vci_lagrangian_t
  use vci_observer, only: vci_observer_t, vci_run_info_t, vci_impact_t
  use vci_checkpoint, only: vci_checkpoint_t
  use vci_integrator, only: vci_integrator_t, vci_stats_t, VCI_IMPACT_DISCRETE, VCI_IMPACT_HAMILTONIAN
  use vci_callback_adapter, only: vci_callback_record_t
  use vci, only: VCI_VERSION_NUMBER
#ifdef VCI_HAVE_HDF5
  use vci_hdf5_output, only: vci_hdf5_writer_t
#endif
  implicit none
  private

  public :: vci_model_create_v2, vci_model_create_v0_1, vci_model_create_lagrangian, vci_model_destroy
  public :: vci_set_scheme
  public :: vci_integrator_create, vci_integrator_destroy
  public :: vci_set_tolerances, vci_set_impact_energy, vci_set_max_impacts
  public :: vci_init_from_pair, vci_init_from_momentum, vci_step, vci_integrate
  public :: vci_get_state, vci_get_multipliers, vci_get_energy, vci_get_index, vci_get_stats
  public :: vci_get_energy_fallbacks
  public :: vci_set_impact_callback, vci_open_output, vci_close_output
  public :: vci_last_error, vci_status_string, vci_version

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
  end type vci_lagrangian_callbacks_c

  !> The C signatures of the callbacks (vci.h); each returns 0, > 0 (recoverable) or < 0.
  !> (L, dL/dq and dL/dqdot have c_energy_fn's shape: n, q, v, out, user.)
  abstract interface
    integer(c_int) function c_lhess_fn(n, q, v, lqq, lqv, lvv, user) bind(C)
      import :: c_int, c_double, c_ptr
      integer(c_int), value :: n
      real(c_double), intent(in) :: q(*), v(*)
      real(c_double), intent(inout) :: lqq(*), lqv(*), lvv(*)
      type(c_ptr), value :: user
    end function c_lhess_fn
    integer(c_int) function c_ld_grad_fn(n, q, v, h, out, user) bind(C)
      import :: c_int, c_double, c_ptr
      integer(c_int), value :: n
      real(c_double), intent(in) :: q(*), v(*)
      real(c_double), value :: h
      real(c_double), intent(inout) :: out(*)
      type(c_ptr), value :: user
    end function c_ld_grad_fn
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

  ! src/bindings/vci_capi_sync.c
  interface
    pure integer(c_size_t) function c_strlen(s) bind(C, name='strlen')
      import :: c_size_t, c_ptr
      type(c_ptr), value, intent(in) :: s
    end function c_strlen
    subroutine lock_registry() bind(C, name='vci_lock_registry')
    end subroutine lock_registry
    subroutine unlock_registry() bind(C, name='vci_unlock_registry')
    end subroutine unlock_registry
    subroutine lock_io() bind(C, name='vci_lock_io')
    end subroutine lock_io
    subroutine unlock_io() bind(C, name='vci_unlock_io')
    end subroutine unlock_io
    subroutine c_set_thread_message(msg, len) bind(C, name='vci_set_thread_message')
      import :: c_char, c_int
      character(kind=c_char), intent(in) :: msg(*)
      integer(c_int), value :: len
    end subroutine c_set_thread_message
    integer(c_int) function c_get_thread_message(buf, size) bind(C, name='vci_get_thread_message')
      import :: c_char, c_int
      character(kind=c_char), intent(inout) :: buf(*)
      integer(c_int), value :: size
    end function c_get_thread_message
  end interface

  !> The model behind a `vci_model` handle (immutable once created), and each integrator's own
  !> copy of it: C function pointers, user pointer, and the integrator's callback record.
  !> A continuous model's handle is a c_model_t too (continuous = .true., callbacks in lcb): the
  !> registry, copies and destroy are the same; an integrator made from it drives a c_lagrangian_t.
  type, extends(vci_model_t) :: c_model_t
    type(vci_callbacks_c) :: cb
    logical :: continuous = .false.
    type(vci_lagrangian_callbacks_c) :: lcb
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
    procedure :: gaps => cm_gaps
    procedure :: gap_gradients => cm_gap_grads
    procedure :: energy => cm_energy
  end type c_model_t

  !> Forwards impacts to the C impact callback and everything to the output file, if any. The
  !> output sees one run from vci_open_output to vci_close_output/destroy, however many
  !> vci_step/vci_integrate calls it spans (all in one direction, from one initialisation).
  type, extends(vci_observer_t) :: c_observer_t
    type(c_funptr) :: impact_fn = c_null_funptr
    type(c_ptr) :: user = c_null_ptr
    integer(c_int) :: impact_rc = 0
    real(dp) :: impact_t = 0.0_dp
    class(vci_observer_t), allocatable :: output
    logical :: started = .false.
    integer :: direction = 0               !< of the output's run, once started
    type(c_integrator_t), pointer :: owner => null()
    logical :: stopped_by_destroy = .false.
  contains
    procedure :: on_start => obs_start
    procedure :: on_step => obs_step
    procedure :: on_impact => obs_impact
    procedure :: on_finish => obs_finish
    procedure :: keeps_checkpoints => obs_keeps_checkpoints
    procedure :: wants_checkpoint => obs_wants_checkpoint
    procedure :: on_checkpoint => obs_checkpoint
    procedure :: failure_cause => obs_failure_cause
  end type c_observer_t

  !> The C continuous model: extends vci_lagrangian_t as c_model_t extends vci_model_t; the return
  !> codes go through the same adapter, into the record of its integrator's model copy.
  type, extends(vci_lagrangian_t) :: c_lagrangian_t
    type(vci_lagrangian_callbacks_c) :: cb
    type(c_ptr) :: user = c_null_ptr
    type(vci_callback_record_t), pointer :: record => null()
  contains
    procedure :: lagrangian => cl_value
    procedure :: dl_dq => cl_dl_dq
    procedure :: dl_dv => cl_dl_dv
    procedure :: hessians => cl_hessians
    procedure :: constraint_forms => cl_forms
    procedure :: gaps => cl_gaps
    procedure :: gap_gradients => cl_gap_grads
    procedure :: energy => cl_energy
  end type c_lagrangian_t

  type :: c_integrator_t
    type(vci_integrator_t) :: integ
    type(c_model_t) :: model              !< this integrator's own copy of the model (and its record)
    type(c_lagrangian_t) :: lag           !< the continuous model it drives, when model%continuous
    type(c_observer_t) :: obs
    logical :: busy = .false.             !< a call on it is running (guarded by the registry lock)
    logical :: destroy_pending = .false.  !< destroyed while busy: freed when that call returns
  end type c_integrator_t

  ! The registry: a handle is the token serial * 2**slot_bits + slot; slot 0 is never used, so no
  ! handle is NULL. Serial numbers grow by one per created object and are never reused.
  integer, parameter :: KIND_MODEL = 1, KIND_INTEGRATOR = 2
  integer, parameter :: slot_bits = merge(20, 12, bit_size(0_c_intptr_t) > 32)
  integer(c_intptr_t), parameter :: slot_mask = 2_c_intptr_t**slot_bits - 1
  integer(c_intptr_t), parameter :: max_serial = huge(0_c_intptr_t) / 2_c_intptr_t**slot_bits
  type :: slot_t
    integer(c_intptr_t) :: serial = 0      !< 0: free
    integer :: kind = 0
    type(c_model_t), pointer :: model => null()
    type(c_integrator_t), pointer :: integ => null()
  end type slot_t
  type(slot_t), allocatable, save :: slots(:)
  integer, save :: n_live = 0
  integer(c_intptr_t), save :: last_serial = 0

  ! NUL-terminated status strings handed out by vci_status_string: initialised at load time, read-only
  integer, parameter :: STATUS_LEN = 40
  integer, parameter :: N_STATUS = ubound(VCI_STATUS_NAMES, 1)
  integer :: i_
  character(kind=c_char, len=STATUS_LEN), target, save :: status_text(0:N_STATUS + 1) = &
    [character(kind=c_char, len=STATUS_LEN) :: (trim(VCI_STATUS_NAMES(i_))//c_null_char, i_ = 0, N_STATUS), &
     'unknown status'//c_null_char]

contains

  ! ---------------------------------------------------------------------------------------------
  ! the calling thread's message (failures without a live integrator)

  subroutine set_thread_message(msg)
    character(len=*), intent(in) :: msg
    character(kind=c_char) :: buf(max(1, len_trim(msg)))
    integer :: i
    do i = 1, len_trim(msg)
      buf(i) = msg(i:i)
    end do
    call c_set_thread_message(buf, int(len_trim(msg), c_int))
  end subroutine set_thread_message

  function thread_message() result(msg)
    character(len=VCI_MSG_LEN) :: msg
    character(kind=c_char) :: buf(VCI_MSG_LEN)
    integer :: i, n
    n = c_get_thread_message(buf, int(VCI_MSG_LEN, c_int))
    msg = ''
    do i = 1, n
      msg(i:i) = buf(i)
    end do
  end function thread_message

  ! ---------------------------------------------------------------------------------------------
  ! the registry (every procedure here runs with the registry lock held)

  !> The slot a handle names if it is live and of the given kind, else 0.
  integer function find_live(handle, kind) result(i)
    type(c_ptr), intent(in) :: handle
    integer, intent(in) :: kind
    integer(c_intptr_t) :: token, slot
    i = 0
    if (.not. c_associated(handle) .or. .not. allocated(slots)) return
    token = transfer(handle, token)
    if (token <= 0) return
    slot = iand(token, slot_mask)
    if (slot < 1 .or. slot > size(slots)) return
    if (slots(slot)%serial /= shiftr(token, slot_bits) .or. slots(slot)%kind /= kind) return
    i = int(slot)
  end function find_live

  !> Take a free slot for a new object; its handle, or C NULL when the registry is full.
  function register(kind, mp, ip) result(handle)
    integer, intent(in) :: kind
    type(c_model_t), pointer, intent(in) :: mp
    type(c_integrator_t), pointer, intent(in) :: ip
    type(c_ptr) :: handle
    type(slot_t), allocatable :: grown(:)
    integer :: i, st
    handle = c_null_ptr
    if (.not. allocated(slots)) then
      allocate (slots(16), stat=st)
      if (st /= 0) return
    end if
    i = 0
    if (n_live < size(slots)) then
      do i = 1, size(slots)
        if (slots(i)%serial == 0) exit
      end do
    end if
    if (i < 1 .or. i > size(slots)) then
      if (2_c_intptr_t * size(slots) > slot_mask) return      ! 2**slot_bits - 1 live handles at most
      allocate (grown(2 * size(slots)), stat=st)
      if (st /= 0) return
      grown(1:size(slots)) = slots
      i = size(slots) + 1
      call move_alloc(grown, slots)
    end if
    last_serial = last_serial + 1
    if (last_serial > max_serial) last_serial = 1             ! after ~8.8e12 handles (64-bit)
    slots(i)%serial = last_serial
    slots(i)%kind = kind
    slots(i)%model => mp
    slots(i)%integ => ip
    n_live = n_live + 1
    handle = transfer(last_serial * 2_c_intptr_t**slot_bits + i, handle)
  end function register

  subroutine unregister(i)
    integer, intent(in) :: i
    slots(i) = slot_t()
    n_live = n_live - 1
    if (n_live == 0) deallocate (slots)   ! nothing left behind at exit
  end subroutine unregister

  ! ---------------------------------------------------------------------------------------------
  ! entering and leaving a call on an integrator

  !> Look the handle up and mark the integrator busy; on failure a status and the thread's message.
  !> Every successful enter is paired with one leave. The call starts with a clean slate: status
  !> OK, empty message, empty callback record.
  subroutine enter(handle, who, ip, stat)
    type(c_ptr), intent(in) :: handle
    character(len=*), intent(in) :: who
    type(c_integrator_t), pointer, intent(out) :: ip
    integer, intent(out) :: stat
    integer :: i
    ip => null()
    stat = VCI_OK
    call lock_registry()
    i = find_live(handle, KIND_INTEGRATOR)
    if (i > 0) then
      ip => slots(i)%integ
      if (ip%busy) then
        ip => null()
        stat = VCI_ERR_STATE
      else
        ip%busy = .true.
      end if
    end if
    call unlock_registry()
    if (.not. c_associated(handle)) then
      call set_thread_message(who//': the integrator handle is NULL')
      stat = VCI_ERR_ARGUMENT
    else if (stat == VCI_ERR_STATE) then
      call set_thread_message(who//': the integrator is busy: a call on it is running (it may not be '// &
                              'called from its own callbacks, nor from two threads at once)')
    else if (i == 0) then
      call set_thread_message(who//': not a live integrator handle (destroyed, or not made by '// &
                              'vci_integrator_create)')
      stat = VCI_ERR_ARGUMENT
    else
      call ip%integ%report_failure(VCI_OK, '')
      call ip%model%record%clear()
    end if
  end subroutine enter

  !> The call on ip is over: not busy any more, and freed if it was destroyed meanwhile.
  subroutine leave(ip)
    type(c_integrator_t), pointer, intent(inout) :: ip
    logical :: free_it
    call lock_registry()
    ip%busy = .false.
    free_it = ip%destroy_pending
    call unlock_registry()
    if (free_it) call free_integrator(ip)
    ip => null()
  end subroutine leave

  !> Record a failure detected in this layer on the integrator (read back with vci_last_error).
  integer function fail(ip, status, message)
    type(c_integrator_t), intent(inout) :: ip
    integer, intent(in) :: status
    character(len=*), intent(in) :: message
    call ip%integ%report_failure(status, message)
    fail = status
  end function fail

  !> After a call into the integrator: name the C callback behind a callback failure (its code),
  !> and report a failing impact callback as VCI_ERR_CALLBACK, not as an output error. The status
  !> of the call itself; the integrator's status and message follow it.
  integer function after_call(ip, stat) result(status)
    type(c_integrator_t), intent(inout) :: ip
    integer, intent(in) :: stat
    character(len=32) :: rc
    character(len=VCI_MSG_LEN) :: msg
    status = stat
    msg = ip%integ%message_text()
    if (ip%obs%stopped_by_destroy) then
      status = VCI_ERR_STATE
      call set_thread_message('the integrator was destroyed during the call (from a callback or another '// &
                              'thread); the run stopped after the step under way')
    else if (stat == VCI_ERR_IO .and. ip%obs%impact_rc /= 0) then
      write (rc, '(i0)') ip%obs%impact_rc
      write (msg, '(a,es14.7,a)') 'impact callback returned '//trim(rc)//' at the impact at t = ', &
        ip%obs%impact_t, '; the step containing it was accepted, the state is after it'
      status = VCI_ERR_CALLBACK
    else
      call ip%model%record%annotate(stat, msg)
    end if
    call ip%integ%report_failure(status, msg)
    ip%obs%impact_rc = 0
  end function after_call

  !> A C array of n doubles as a Fortran pointer; false when NULL.
  logical function c_array(p, n, arr)
    type(c_ptr), intent(in) :: p
    integer, intent(in) :: n
    real(c_double), pointer, intent(out) :: arr(:)
    arr => null()
    c_array = c_associated(p)
    if (c_array) call c_f_pointer(p, arr, [n])
  end function c_array

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
    integer :: rc
    lqq = 0.0_dp; lqv = 0.0_dp; lvv = 0.0_dp   ! defined even where a failing callback left them unwritten
    if (.not. c_associated(self%cb%hessians)) then
      call self%not_provided(stat); return
    end if
    call c_f_procpointer(self%cb%hessians, f)
    rc = f(self%n, q, v, lqq, lqv, lvv, self%user)
    call self%record%note(rc, 'the C callback hessians', all(ieee_is_finite(lqq)) .and. &
                          all(ieee_is_finite(lqv)) .and. all(ieee_is_finite(lvv)), stat)
  end subroutine cl_hessians

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
  ! the observer behind vci_set_impact_callback and vci_open_output

  subroutine obs_start(self, info, q, p, stat)
    class(c_observer_t), intent(inout) :: self
    type(vci_run_info_t), intent(in) :: info
    real(dp), intent(in) :: q(:), p(:)
    integer, intent(inout) :: stat
    if (.not. allocated(self%output) .or. self%started) return
    call lock_io()
    call self%output%on_start(info, q, p, stat)
    call unlock_io()
    self%started = .true.
    self%direction = info%direction
  end subroutine obs_start

  !> An accepted step: to the output; the callback record starts afresh (a code the line search
  !> absorbed in this step is no cause of a later failure); stop when destroyed meanwhile.
  subroutine obs_step(self, step, t, q, p, lambda, energy, stat)
    class(c_observer_t), intent(inout) :: self
    integer(i8), intent(in) :: step
    real(dp), intent(in) :: t, q(:), p(:), lambda(:), energy
    integer, intent(inout) :: stat
    logical :: pending
    if (allocated(self%output)) then
      call lock_io()
      call self%output%on_step(step, t, q, p, lambda, energy, stat)
      call unlock_io()
    end if
    if (associated(self%owner)) then
      call self%owner%model%record%clear()
      call lock_registry()
      pending = self%owner%destroy_pending
      call unlock_registry()
      if (pending .and. stat == 0) then
        self%stopped_by_destroy = .true.
        stat = 1
      end if
    end if
  end subroutine obs_step

  subroutine obs_impact(self, impact, stat)
    class(c_observer_t), intent(inout) :: self
    type(vci_impact_t), intent(in) :: impact
    integer, intent(inout) :: stat
    procedure(c_impact_fn), pointer :: f
    integer(c_int) :: rc
    if (c_associated(self%impact_fn) .and. stat == 0) then
      call c_f_procpointer(self%impact_fn, f)
      ! C numbers the gaps from 0, as in the g[] array of vci_gaps_fn
      rc = f(impact%t, impact%alpha, int(impact%gap - 1, c_int), impact%q, impact%impulse, self%user)
      if (rc /= 0) then
        self%impact_rc = rc; self%impact_t = impact%t
        stat = 1; return
      end if
    end if
    if (allocated(self%output) .and. stat == 0) then
      call lock_io()
      call self%output%on_impact(impact, stat)
      call unlock_io()
    end if
  end subroutine obs_impact

  ! checkpoints go to the output (HDF5 stores them: restarts from its file continue bit for bit)
  pure logical function obs_keeps_checkpoints(self)
    class(c_observer_t), intent(in) :: self
    obs_keeps_checkpoints = .false.
    if (allocated(self%output)) obs_keeps_checkpoints = self%output%keeps_checkpoints()
  end function obs_keeps_checkpoints

  pure logical function obs_wants_checkpoint(self)
    class(c_observer_t), intent(in) :: self
    obs_wants_checkpoint = .false.
    if (allocated(self%output)) obs_wants_checkpoint = self%output%wants_checkpoint()
  end function obs_wants_checkpoint

  subroutine obs_checkpoint(self, cp, stat)
    class(c_observer_t), intent(inout) :: self
    type(vci_checkpoint_t), intent(in) :: cp
    integer, intent(inout) :: stat
    if (allocated(self%output)) call self%output%on_checkpoint(cp, stat)
  end subroutine obs_checkpoint

  subroutine obs_failure_cause(self, cause)
    class(c_observer_t), intent(in) :: self
    character(len=*), intent(out) :: cause
    cause = ''
    if (allocated(self%output)) call self%output%failure_cause(cause)
  end subroutine obs_failure_cause

  !> Runs end at vci_close_output or destroy, not at the end of each vci_integrate call.
  subroutine obs_finish(self, status, message, stat)
    class(c_observer_t), intent(inout) :: self
    integer, intent(in) :: status
    character(len=*), intent(in) :: message
    integer, intent(inout) :: stat
  end subroutine obs_finish

  !> Finish and drop the output of an integrator; the status of closing it.
  integer function close_output(ip) result(stat)
    type(c_integrator_t), intent(inout) :: ip
    stat = 0
    if (.not. allocated(ip%obs%output)) return
    ! also when no step was written: the writer then just closes its file
    call lock_io()
    if (ip%obs%started .and. ip%obs%output%keeps_checkpoints()) &
      call ip%obs%output%on_checkpoint(ip%integ%checkpoint(), stat)
    stat = 0
    call ip%obs%output%on_finish(ip%integ%status(), trim(ip%integ%message_text()), stat)
    deallocate (ip%obs%output)
    call unlock_io()
    ip%obs%started = .false.
    ip%obs%direction = 0
    if (stat /= 0) stat = VCI_ERR_IO
  end function close_output

  !> Close the output and release an integrator no handle names any more.
  subroutine free_integrator(ip)
    type(c_integrator_t), pointer, intent(inout) :: ip
    integer :: stat
    stat = close_output(ip)
    if (stat /= VCI_OK) call set_thread_message('vci_integrator_destroy: the output file could not be finished')
    deallocate (ip)
  end subroutine free_integrator

  ! ---------------------------------------------------------------------------------------------
  ! the C entry points (vci.h documents each one's statuses)

  !> int vci_model_create_v2(vci_model *model, int n, int m, int ngaps, const vci_callbacks *cb,
  !> void *user): vci.h's vci_model_create. Reads cb->size bytes of the callbacks.
  integer(c_int) function vci_model_create_v2(model, n, m, ngaps, cb, user) bind(C, name='vci_model_create_v2')
    type(c_ptr), value :: model, cb, user
    integer(c_int), value :: n, m, ngaps
    type(vci_callbacks_c), target :: local
    integer(c_size_t), pointer :: size_field
    integer(c_int8_t), pointer :: src(:), dst(:)
    integer(c_size_t) :: nbytes, ours, least
    character(len=24) :: txt
    integer :: k
    vci_model_create_v2 = VCI_ERR_ARGUMENT
    if (.not. c_associated(model)) then
      call set_thread_message('vci_model_create: the model argument is NULL'); return
    end if
    call null_out(model)
    if (.not. c_associated(cb)) then
      call set_thread_message('vci_model_create: the callbacks argument is NULL'); return
    end if
    call c_f_pointer(cb, size_field)
    nbytes = size_field
    ours = c_sizeof(local)
    least = c_sizeof(local%size) + 3 * c_sizeof(c_null_funptr)   ! up to d3_ld: the required ones
    write (txt, '(i0)') nbytes
    ! every header's struct is the size field and whole pointers: anything else is no vci_callbacks
    if (nbytes < least .or. nbytes > 4096 .or. &
        mod(nbytes - c_sizeof(local%size), c_sizeof(c_null_funptr)) /= 0) then
      call set_thread_message('vci_model_create: cb->size = '//trim(txt)//' is not the size of a vci_callbacks '// &
                              '(initialise it with VCI_CALLBACKS_INIT)')
      return
    end if
    call c_f_pointer(cb, src, [nbytes])
    if (nbytes > ours) then
      ! built against a newer vci.h: fine as long as the members this library does not know are NULL
      if (any(src(ours + 1:nbytes) /= 0)) then
        call set_thread_message('vci_model_create: callbacks this library does not know are set (cb->size = '// &
                                trim(txt)//'; the program was built against a newer vci.h)')
        return
      end if
    end if
    local = vci_callbacks_c()
    call c_f_pointer(c_loc(local), dst, [ours])
    k = int(min(nbytes, ours))
    dst(1:k) = src(1:k)
    local%size = ours
    vci_model_create_v2 = create_model('vci_model_create', model, n, m, ngaps, local, user)
  end function vci_model_create_v2

  !> int vci_model_create(...) as vci.h 0.1.0 declared it: the callbacks are nine pointers with no
  !> size field. Kept (under its 0.1 symbol name) for binaries built against 0.1.
  integer(c_int) function vci_model_create_v0_1(model, n, m, ngaps, cb, user) bind(C, name='vci_model_create')
    type(c_ptr), value :: model, cb, user
    integer(c_int), value :: n, m, ngaps
    type(vci_callbacks_v0_1), pointer :: old
    type(vci_callbacks_c) :: local
    vci_model_create_v0_1 = VCI_ERR_ARGUMENT
    if (.not. c_associated(model)) then
      call set_thread_message('vci_model_create: the model argument is NULL'); return
    end if
    call null_out(model)
    if (.not. c_associated(cb)) then
      call set_thread_message('vci_model_create: the callbacks argument is NULL'); return
    end if
    call c_f_pointer(cb, old)
    local = vci_callbacks_c(c_sizeof(local), old%d1_ld, old%d2_ld, old%d3_ld, old%mixed_hessian, &
                            old%constraint_forms, old%discrete_constraint, old%gaps, old%gap_gradients, old%energy)
    vci_model_create_v0_1 = create_model('vci_model_create', model, n, m, ngaps, local, user)
  end function vci_model_create_v0_1

  !> int vci_model_create_lagrangian(vci_model *model, int n, int m, int ngaps,
  !> const vci_lagrangian_callbacks *cb, void *user). Reads cb->size bytes of the callbacks (the
  !> rules of vci_model_create_v2).
  integer(c_int) function vci_model_create_lagrangian(model, n, m, ngaps, cb, user) &
    bind(C, name='vci_model_create_lagrangian')
    type(c_ptr), value :: model, cb, user
    integer(c_int), value :: n, m, ngaps
    type(vci_lagrangian_callbacks_c) :: local
    type(c_funptr), pointer :: fps(:)
    integer(c_size_t), pointer :: size_field
    integer(c_int8_t), pointer :: src(:)
    integer(c_size_t) :: nbytes, ours, least
    character(len=24) :: txt
    character(len=64) :: what
    integer :: k, i
    vci_model_create_lagrangian = VCI_ERR_ARGUMENT
    if (.not. c_associated(model)) then
      call set_thread_message('vci_model_create_lagrangian: the model argument is NULL'); return
    end if
    call null_out(model)
    if (.not. c_associated(cb)) then
      call set_thread_message('vci_model_create_lagrangian: the callbacks argument is NULL'); return
    end if
    call c_f_pointer(cb, size_field)
    nbytes = size_field
    ours = c_sizeof(local)
    least = c_sizeof(local%size) + 3 * c_sizeof(c_null_funptr)   ! up to dl_dv: the required ones
    write (txt, '(i0)') nbytes
    if (nbytes < least .or. nbytes > 4096) then
      call set_thread_message('vci_model_create_lagrangian: cb->size = '//trim(txt)//' is not the size of a '// &
                              'vci_lagrangian_callbacks (initialise it with VCI_LAGRANGIAN_CALLBACKS_INIT)')
      return
    end if
    call c_f_pointer(cb, src, [nbytes])
    if (nbytes > ours) then
      if (any(src(ours + 1:nbytes) /= 0)) then
        call set_thread_message('vci_model_create_lagrangian: callbacks this library does not know are set '// &
                                '(cb->size = '//trim(txt)//'; the program was built against a newer vci.h)')
        return
      end if
    end if
    ! the members the caller's header has (those beyond its size stay NULL), one by one: a byte copy
    ! into `local` through a second pointer was lost to gfortran's optimiser
    k = int((min(nbytes, ours) - c_sizeof(local%size)) / c_sizeof(c_null_funptr))
    call c_f_pointer(transfer(transfer(cb, 0_c_intptr_t) + c_sizeof(local%size), cb), fps, [k])
    local = vci_lagrangian_callbacks_c()
    local%size = ours
    do i = 1, k
      select case (i)
      case (1); local%lagrangian = fps(i)
      case (2); local%dl_dq = fps(i)
      case (3); local%dl_dv = fps(i)
      case (4); local%hessians = fps(i)
      case (5); local%constraint_forms = fps(i)
      case (6); local%gaps = fps(i)
      case (7); local%gap_gradients = fps(i)
      case (8); local%energy = fps(i)
      end select
    end do
    what = ''
    if (.not. c_associated(local%lagrangian)) what = 'lagrangian'
    if (.not. c_associated(local%dl_dq)) what = 'dl_dq'
    if (.not. c_associated(local%dl_dv)) what = 'dl_dv'
    if (m > 0 .and. .not. c_associated(local%constraint_forms)) what = 'constraint_forms (needed as m > 0)'
    if (ngaps > 0 .and. .not. c_associated(local%gaps)) what = 'gaps (needed as ngaps > 0)'
    if (what /= '') then
      call set_thread_message('vci_model_create_lagrangian: callback '//trim(what)//' is NULL (lagrangian, '// &
                              'dl_dq and dl_dv are required)')
      return
    end if
    ! sizes, allocation and registry as for a discrete model
    vci_model_create_lagrangian = create_model('vci_model_create_lagrangian', model, n, m, ngaps, vci_callbacks_c(), user, local)
  end function vci_model_create_lagrangian

  !> *out = NULL for the handle pointer `out` (not NULL).
  subroutine null_out(out)
    type(c_ptr), intent(in) :: out
    type(c_ptr), pointer :: h
    call c_f_pointer(out, h)
    h = c_null_ptr
  end subroutine null_out

  !> The model_create entry points (`caller`: the one called): validate, allocate, register.
  !> With lcb: a continuous model (its callbacks already checked; fcb unused).
  integer function create_model(caller, model, n, m, ngaps, fcb, user, lcb) result(status)
    character(len=*), intent(in) :: caller   !< the C entry point called, named in messages
    type(c_ptr), intent(in) :: model, user
    integer(c_int), intent(in) :: n, m, ngaps
    type(vci_callbacks_c), intent(in) :: fcb
    type(vci_lagrangian_callbacks_c), intent(in), optional :: lcb
    type(c_ptr), pointer :: out
    type(c_model_t), pointer :: mp
    type(c_integrator_t), pointer :: none
    character(len=64) :: what
    character(len=80) :: why
    integer :: st
    status = VCI_ERR_ARGUMENT
    why = vci_size_problem(int(n), int(m), int(ngaps))
    if (why /= '') then
      block
        character(len=VCI_MSG_LEN) :: msg
        write (msg, '(a,3(i0,a))') caller//': sizes n = ', n, ', m = ', m, ', ngaps = ', ngaps, &
          ' invalid ('//trim(why)//')'
        call set_thread_message(msg)
      end block
      return
    end if
    what = ''
    if (.not. present(lcb)) then
      if (.not. c_associated(fcb%d1_ld)) what = 'd1_ld'
      if (.not. c_associated(fcb%d2_ld)) what = 'd2_ld'
      if (.not. c_associated(fcb%d3_ld)) what = 'd3_ld'
      if (m > 0 .and. .not. c_associated(fcb%constraint_forms)) what = 'constraint_forms (needed as m > 0)'
      if (m > 0 .and. .not. c_associated(fcb%discrete_constraint)) what = 'discrete_constraint (needed as m > 0)'
      if (ngaps > 0 .and. .not. c_associated(fcb%gaps)) what = 'gaps (needed as ngaps > 0)'
    end if
    if (what /= '') then
      call set_thread_message(caller//': callback '//trim(what)//' is NULL'); return
    end if
    allocate (mp, stat=st)
    if (st /= 0) then
      call set_thread_message(caller//': out of memory')
      status = VCI_ERR_MEMORY; return
    end if
    mp%n = n; mp%m = m; mp%n_gaps = ngaps
    mp%cb = fcb
    mp%user = user
    if (present(lcb)) then
      mp%continuous = .true.
      mp%lcb = lcb
    end if
    none => null()
    call c_f_pointer(model, out)
    call lock_registry()
    out = register(KIND_MODEL, mp, none)
    call unlock_registry()
    if (.not. c_associated(out)) then
      deallocate (mp)
      call set_thread_message(caller//': too many live handles, or out of memory')
      status = VCI_ERR_MEMORY; return
    end if
    status = VCI_OK
  end function create_model

  !> void vci_model_destroy(vci_model *model): NULL-safe, sets *model = NULL. Integrators made
  !> from the model keep their own copy of it.
  subroutine vci_model_destroy(model) bind(C, name='vci_model_destroy')
    type(c_ptr), value :: model
    type(c_ptr), pointer :: h
    type(c_model_t), pointer :: mp
    integer :: i
    if (.not. c_associated(model)) return
    call c_f_pointer(model, h)
    if (.not. c_associated(h)) return
    mp => null()
    call lock_registry()
    i = find_live(h, KIND_MODEL)
    if (i > 0) then
      mp => slots(i)%model
      call unregister(i)
    end if
    call unlock_registry()
    if (associated(mp)) then
      deallocate (mp)
    else
      call set_thread_message('vci_model_destroy: not a live model handle (destroyed twice?); ignored')
    end if
    h = c_null_ptr
  end subroutine vci_model_destroy

  !> int vci_integrator_create(vci_integrator *integ, vci_model model, double h)
  integer(c_int) function vci_integrator_create(integ, model, h) bind(C, name='vci_integrator_create')
    type(c_ptr), value :: integ, model
    real(c_double), value :: h
    type(c_ptr), pointer :: out
    type(c_model_t), pointer :: none
    type(c_integrator_t), pointer :: ip
    integer :: stat, i
    vci_integrator_create = VCI_ERR_ARGUMENT
    if (.not. c_associated(integ)) then
      call set_thread_message('vci_integrator_create: the integ argument is NULL'); return
    end if
    call c_f_pointer(integ, out)
    out = c_null_ptr
    allocate (ip, stat=stat)
    if (stat /= 0) then
      call set_thread_message('vci_integrator_create: out of memory')
      vci_integrator_create = VCI_ERR_MEMORY; return
    end if
    ! the integrator's own copy of the model, taken under the lock (the model may be destroyed
    ! by another thread at the same time)
    call lock_registry()
    i = find_live(model, KIND_MODEL)
    if (i > 0) ip%model = slots(i)%model
    call unlock_registry()
    if (i == 0) then
      deallocate (ip)
      if (.not. c_associated(model)) then
        call set_thread_message('vci_integrator_create: the model handle is NULL')
      else
        call set_thread_message('vci_integrator_create: not a live model handle (destroyed, or not made by '// &
                                'vci_model_create or vci_model_create_lagrangian)')
      end if
      return
    end if
    call ip%model%record%clear()
    if (ip%model%continuous) then
      ip%lag%n = ip%model%n; ip%lag%m = ip%model%m; ip%lag%n_gaps = ip%model%n_gaps
      ip%lag%cb = ip%model%lcb
      ip%lag%user = ip%model%user
      ip%lag%record => ip%model%record
      call ip%integ%create(ip%lag, real(h, dp), stat)
    else
      call ip%integ%create(ip%model, real(h, dp), stat)
    end if
    if (stat /= VCI_OK) then
      call set_thread_message('vci_integrator_create: '//trim(ip%integ%message_text()))
      deallocate (ip)
      vci_integrator_create = stat; return
    end if
    ip%obs%owner => ip
    none => null()
    call lock_registry()
    out = register(KIND_INTEGRATOR, none, ip)
    call unlock_registry()
    if (.not. c_associated(out)) then
      deallocate (ip)
      call set_thread_message('vci_integrator_create: too many live handles, or out of memory')
      vci_integrator_create = VCI_ERR_MEMORY; return
    end if
    vci_integrator_create = VCI_OK
  end function vci_integrator_create

  !> void vci_integrator_destroy(vci_integrator *integ): NULL-safe, sets *integ = NULL; closes
  !> output. The handle is dead at once; an integrator that is running a call (destroyed from one
  !> of its callbacks, or from another thread) is freed when that call returns.
  subroutine vci_integrator_destroy(integ) bind(C, name='vci_integrator_destroy')
    type(c_ptr), value :: integ
    type(c_ptr), pointer :: h
    type(c_integrator_t), pointer :: ip
    integer :: i
    logical :: free_now
    if (.not. c_associated(integ)) return
    call c_f_pointer(integ, h)
    if (.not. c_associated(h)) return
    ip => null()
    free_now = .false.
    call lock_registry()
    i = find_live(h, KIND_INTEGRATOR)
    if (i > 0) then
      ip => slots(i)%integ
      call unregister(i)
      if (ip%busy) then
        ip%destroy_pending = .true.
      else
        free_now = .true.
      end if
    end if
    call unlock_registry()
    if (i == 0) call set_thread_message('vci_integrator_destroy: not a live integrator handle (destroyed twice?); '// &
                                        'ignored')
    if (free_now) call free_integrator(ip)
    h = c_null_ptr
  end subroutine vci_integrator_destroy

  !> int vci_set_tolerances(vci_integrator integ, double atol, double rtol, int max_iterations)
  integer(c_int) function vci_set_tolerances(integ, atol, rtol, max_iterations) bind(C, name='vci_set_tolerances')
    type(c_ptr), value :: integ
    real(c_double), value :: atol, rtol
    integer(c_int), value :: max_iterations
    type(c_integrator_t), pointer :: ip
    integer :: stat
    call enter(integ, 'vci_set_tolerances', ip, stat)
    if (stat == VCI_OK) then
      call ip%integ%set_tolerances(real(atol, dp), real(rtol, dp), int(max_iterations), stat)
      call leave(ip)
    end if
    vci_set_tolerances = stat
  end function vci_set_tolerances

  !> int vci_set_impact_energy(vci_integrator integ, int mode): 0 discrete (default), 1 hamiltonian.
  integer(c_int) function vci_set_impact_energy(integ, mode) bind(C, name='vci_set_impact_energy')
    type(c_ptr), value :: integ
    integer(c_int), value :: mode
    type(c_integrator_t), pointer :: ip
    integer :: stat
    call enter(integ, 'vci_set_impact_energy', ip, stat)
    if (stat == VCI_OK) then
      call ip%integ%set_impact_energy(int(mode), stat)
      call leave(ip)
    end if
    vci_set_impact_energy = stat
  end function vci_set_impact_energy

  !> int vci_set_max_impacts(vci_integrator integ, int max_impacts): impacts allowed in one step.
  integer(c_int) function vci_set_max_impacts(integ, max_impacts) bind(C, name='vci_set_max_impacts')
    type(c_ptr), value :: integ
    integer(c_int), value :: max_impacts
    type(c_integrator_t), pointer :: ip
    integer :: stat
    call enter(integ, 'vci_set_max_impacts', ip, stat)
    if (stat == VCI_OK) then
      call ip%integ%set_max_impacts(int(max_impacts), stat)
      call leave(ip)
    end if
    vci_set_max_impacts = stat
  end function vci_set_max_impacts

  !> int vci_set_scheme(vci_integrator integ, int scheme, int stages): the scheme of a continuous model.
  integer(c_int) function vci_set_scheme(integ, scheme, stages) bind(C, name='vci_set_scheme')
    type(c_ptr), value :: integ
    integer(c_int), value :: scheme, stages
    type(c_integrator_t), pointer :: ip
    integer :: stat
    call enter(integ, 'vci_set_scheme', ip, stat)
    if (stat == VCI_OK) then
      if (output_blocks_init(ip, 'vci_set_scheme', stat)) then
        continue
      else if (.not. ip%model%continuous) then
        stat = fail(ip, VCI_ERR_ARGUMENT, 'vci_set_scheme: the model is a discrete L_d (vci_model_create); '// &
                    'schemes discretise a continuous one (vci_model_create_lagrangian)')
      else
        call ip%integ%set_scheme(int(scheme), int(stages), stat)
      end if
      call leave(ip)
    end if
    vci_set_scheme = stat
  end function vci_set_scheme

  !> An output file holds one run from one initialisation: no new start while it has rows.
  logical function output_blocks_init(ip, who, stat)
    type(c_integrator_t), intent(inout) :: ip
    character(len=*), intent(in) :: who
    integer, intent(out) :: stat
    stat = VCI_OK
    output_blocks_init = allocated(ip%obs%output) .and. ip%obs%started
    if (output_blocks_init) stat = fail(ip, VCI_ERR_STATE, who//': the open output file holds the run so far; '// &
                                        'close it (vci_close_output) or open a new one before starting again')
  end function output_blocks_init

  !> int vci_init_from_pair(vci_integrator integ, double t0, const double *q0, const double *q1)
  integer(c_int) function vci_init_from_pair(integ, t0, q0, q1) bind(C, name='vci_init_from_pair')
    type(c_ptr), value :: integ, q0, q1
    real(c_double), value :: t0
    vci_init_from_pair = init_entry(integ, 'vci_init_from_pair', .true., t0, q0, q1)
  end function vci_init_from_pair

  !> int vci_init_from_momentum(vci_integrator integ, double t0, const double *q0, const double *p0)
  integer(c_int) function vci_init_from_momentum(integ, t0, q0, p0) bind(C, name='vci_init_from_momentum')
    type(c_ptr), value :: integ, q0, p0
    real(c_double), value :: t0
    vci_init_from_momentum = init_entry(integ, 'vci_init_from_momentum', .false., t0, q0, p0)
  end function vci_init_from_momentum

  !> The two init entry points (`who`): from the pair (q0 at t0, x1 = q1 at t0 + h) when from_pair,
  !> else from (q0, x1 = p0) at t0.
  integer function init_entry(integ, who, from_pair, t0, q0, x1) result(stat)
    type(c_ptr), intent(in) :: integ, q0, x1
    character(len=*), intent(in) :: who
    logical, intent(in) :: from_pair
    real(c_double), intent(in) :: t0
    type(c_integrator_t), pointer :: ip
    real(c_double), pointer :: a(:), b(:)
    call enter(integ, who, ip, stat)
    if (stat /= VCI_OK) return
    if (.not. (c_array(q0, ip%model%n, a) .and. c_array(x1, ip%model%n, b))) then
      call ip%integ%forget_state()
      stat = fail(ip, VCI_ERR_ARGUMENT, who//': q0 or '//merge('q1', 'p0', from_pair)//' is NULL')
    else if (.not. output_blocks_init(ip, who, stat)) then
      if (from_pair) then
        call ip%integ%init_from_pair(real(t0, dp), a, b, stat)
      else
        call ip%integ%init_from_momentum(real(t0, dp), a, b, stat)
      end if
      stat = after_call(ip, stat)
    end if
    call leave(ip)
  end function init_entry

  !> The output's run goes one way: refuse the other direction while it is open.
  logical function output_blocks_direction(ip, who, direction, stat)
    type(c_integrator_t), intent(inout) :: ip
    character(len=*), intent(in) :: who
    integer, intent(in) :: direction
    integer, intent(out) :: stat
    stat = VCI_OK
    output_blocks_direction = allocated(ip%obs%output) .and. ip%obs%started .and. &
                              (direction == 1 .or. direction == -1) .and. direction /= ip%obs%direction
    if (output_blocks_direction) stat = fail(ip, VCI_ERR_STATE, who//': the open output file holds a run in the '// &
      'other direction; close it (vci_close_output) or open a new one to integrate this way')
  end function output_blocks_direction

  !> int vci_step(vci_integrator integ, int direction)
  integer(c_int) function vci_step(integ, direction) bind(C, name='vci_step')
    type(c_ptr), value :: integ
    integer(c_int), value :: direction
    type(c_integrator_t), pointer :: ip
    integer :: stat, ostat
    call enter(integ, 'vci_step', ip, stat)
    if (stat /= VCI_OK) then
      vci_step = stat; return
    end if
    if (.not. output_blocks_direction(ip, 'vci_step', int(direction), stat)) then
      ! a single step has no on_start of its own: the output's run starts with the first step
      ostat = 0
      if (allocated(ip%obs%output) .and. .not. ip%obs%started .and. ip%integ%is_initialized() .and. &
          (direction == 1 .or. direction == -1)) then
        if (ip%obs%wants_checkpoint()) call ip%obs%on_checkpoint(ip%integ%checkpoint(), ostat)
        if (ostat == 0) call ip%obs%on_start(ip%integ%run_info(int(direction)), ip%integ%configuration(), &
                                             ip%integ%momentum(), ostat)
      end if
      if (ostat /= 0) then
        stat = fail(ip, VCI_ERR_IO, 'vci_step: the output could not start the run: '//trim(output_message(ip)))
      else
        call ip%integ%step(int(direction), stat, ip%obs)
        stat = after_call(ip, stat)
      end if
    end if
    call leave(ip)
    vci_step = stat
  end function vci_step

  !> int vci_integrate(vci_integrator integ, int64_t nsteps, int direction)
  integer(c_int) function vci_integrate(integ, nsteps, direction) bind(C, name='vci_integrate')
    type(c_ptr), value :: integ
    integer(c_int64_t), value :: nsteps
    integer(c_int), value :: direction
    type(c_integrator_t), pointer :: ip
    integer :: stat
    call enter(integ, 'vci_integrate', ip, stat)
    if (stat /= VCI_OK) then
      vci_integrate = stat; return
    end if
    if (.not. output_blocks_direction(ip, 'vci_integrate', int(direction), stat)) then
      call ip%integ%integrate(int(nsteps, i8), int(direction), stat, ip%obs)
      stat = after_call(ip, stat)
    end if
    call leave(ip)
    vci_integrate = stat
  end function vci_integrate

  !> The output writer's own message, if it has one (fixed length: see vci_limits).
  function output_message(ip) result(msg)
    type(c_integrator_t), intent(in) :: ip
    character(len=VCI_MSG_LEN) :: msg
    msg = ''
#ifdef VCI_HAVE_HDF5
    if (allocated(ip%obs%output)) then
      select type (w => ip%obs%output)
      type is (vci_hdf5_writer_t)
        msg = trim(w%message)
      end select
    end if
#endif
  end function output_message

  !> Common checks of the getters: a live, initialised integrator (entered: leave it after).
  subroutine enter_ready(integ, who, ip, stat)
    type(c_ptr), intent(in) :: integ
    character(len=*), intent(in) :: who
    type(c_integrator_t), pointer, intent(out) :: ip
    integer, intent(out) :: stat
    call enter(integ, who, ip, stat)
    if (stat /= VCI_OK) return
    if (.not. ip%integ%is_initialized()) stat = fail(ip, VCI_ERR_STATE, who//': the integrator has no state yet '// &
                                                '(call vci_init_from_pair or vci_init_from_momentum)')
  end subroutine enter_ready

  !> int vci_get_state(vci_integrator integ, double *t, double *q, double *p): NULL outputs are skipped.
  integer(c_int) function vci_get_state(integ, t, q, p) bind(C, name='vci_get_state')
    type(c_ptr), value :: integ, t, q, p
    type(c_integrator_t), pointer :: ip
    real(c_double), pointer :: tt, a(:)
    integer :: stat
    call enter_ready(integ, 'vci_get_state', ip, stat)
    if (stat == VCI_OK) then
      if (c_associated(t)) then
        call c_f_pointer(t, tt); tt = ip%integ%time()
      end if
      if (c_array(q, ip%model%n, a)) a = ip%integ%configuration()
      if (c_array(p, ip%model%n, a)) a = ip%integ%momentum()
    end if
    if (associated(ip)) call leave(ip)
    vci_get_state = stat
  end function vci_get_state

  !> int vci_get_multipliers(vci_integrator integ, double *lambda /* [m] */)
  integer(c_int) function vci_get_multipliers(integ, lambda) bind(C, name='vci_get_multipliers')
    type(c_ptr), value :: integ, lambda
    type(c_integrator_t), pointer :: ip
    real(c_double), pointer :: a(:)
    integer :: stat
    call enter_ready(integ, 'vci_get_multipliers', ip, stat)
    if (stat == VCI_OK) then
      if (ip%model%m > 0) then
        if (c_array(lambda, ip%model%m, a)) then
          a = ip%integ%multipliers()
        else
          stat = fail(ip, VCI_ERR_ARGUMENT, 'vci_get_multipliers: lambda is NULL')
        end if
      end if
    end if
    if (associated(ip)) call leave(ip)
    vci_get_multipliers = stat
  end function vci_get_multipliers

  !> int vci_get_energy(vci_integrator integ, double *energy): E_d of the last step.
  integer(c_int) function vci_get_energy(integ, energy) bind(C, name='vci_get_energy')
    type(c_ptr), value :: integ, energy
    type(c_integrator_t), pointer :: ip
    real(c_double), pointer :: e
    integer :: stat
    call enter_ready(integ, 'vci_get_energy', ip, stat)
    if (stat == VCI_OK) then
      if (c_associated(energy)) then
        call c_f_pointer(energy, e)
        e = ip%integ%energy()
      else
        stat = fail(ip, VCI_ERR_ARGUMENT, 'vci_get_energy: energy is NULL')
      end if
    end if
    if (associated(ip)) call leave(ip)
    vci_get_energy = stat
  end function vci_get_energy

  !> int vci_get_index(vci_integrator integ, int64_t *k): index of the current state (t = t0 + k h).
  integer(c_int) function vci_get_index(integ, k) bind(C, name='vci_get_index')
    type(c_ptr), value :: integ, k
    type(c_integrator_t), pointer :: ip
    integer(c_int64_t), pointer :: kk
    integer :: stat
    call enter_ready(integ, 'vci_get_index', ip, stat)
    if (stat == VCI_OK) then
      if (c_associated(k)) then
        call c_f_pointer(k, kk)
        kk = int(ip%integ%step_index(), c_int64_t)
      else
        stat = fail(ip, VCI_ERR_ARGUMENT, 'vci_get_index: k is NULL')
      end if
    end if
    if (associated(ip)) call leave(ip)
    vci_get_index = stat
  end function vci_get_index

  !> int vci_get_stats(vci_integrator integ, int64_t *steps, int64_t *impacts, int64_t *newton_iterations)
  integer(c_int) function vci_get_stats(integ, steps, impacts, newton_iterations) bind(C, name='vci_get_stats')
    type(c_ptr), value :: integ, steps, impacts, newton_iterations
    type(c_integrator_t), pointer :: ip
    type(vci_stats_t) :: stats
    integer :: stat
    call enter(integ, 'vci_get_stats', ip, stat)
    if (stat == VCI_OK) then
      stats = ip%integ%statistics()
      call put_count(steps, stats%steps)
      call put_count(impacts, stats%impacts)
      call put_count(newton_iterations, stats%newton_iterations)
      call leave(ip)
    end if
    vci_get_stats = stat
  contains
    subroutine put_count(p, v)
      type(c_ptr), intent(in) :: p
      integer(i8), intent(in) :: v
      integer(c_int64_t), pointer :: l
      if (.not. c_associated(p)) return
      call c_f_pointer(p, l)
      l = int(v, c_int64_t)
    end subroutine put_count
  end function vci_get_stats

  !> int vci_get_energy_fallbacks(vci_integrator integ, int64_t *count): impacts where the discrete
  !> energy condition had no solution and H(q, p) was kept instead (docs/DESIGN.md §2).
  integer(c_int) function vci_get_energy_fallbacks(integ, count) bind(C, name='vci_get_energy_fallbacks')
    type(c_ptr), value :: integ, count
    type(c_integrator_t), pointer :: ip
    type(vci_stats_t) :: stats
    integer :: stat
    integer(c_int64_t), pointer :: l
    call enter(integ, 'vci_get_energy_fallbacks', ip, stat)
    if (stat == VCI_OK) then
      if (c_associated(count)) then
        stats = ip%integ%statistics()
        call c_f_pointer(count, l)
        l = int(stats%energy_fallbacks, c_int64_t)
      end if
      call leave(ip)
    end if
    vci_get_energy_fallbacks = stat
  end function vci_get_energy_fallbacks

  !> int vci_set_impact_callback(vci_integrator integ, vci_impact_fn fn, void *user): NULL fn removes it.
  integer(c_int) function vci_set_impact_callback(integ, fn, user) bind(C, name='vci_set_impact_callback')
    type(c_ptr), value :: integ, user
    type(c_funptr), value :: fn
    type(c_integrator_t), pointer :: ip
    integer :: stat
    call enter(integ, 'vci_set_impact_callback', ip, stat)
    if (stat == VCI_OK) then
      ip%obs%impact_fn = fn
      ip%obs%user = user
      call leave(ip)
    end if
    vci_set_impact_callback = stat
  end function vci_set_impact_callback

  !> int vci_open_output(vci_integrator integ, const char *path): HDF5 trajectory file (replaced if
  !> it exists); VCI_ERR_IO when the library was built without HDF5.
  integer(c_int) function vci_open_output(integ, path) bind(C, name='vci_open_output')
    type(c_ptr), value :: integ, path
    type(c_integrator_t), pointer :: ip
    character(kind=c_char), pointer :: chars(:)
    character(len=:), allocatable :: fpath
    integer :: stat, i, nc
    call enter(integ, 'vci_open_output', ip, stat)
    if (stat /= VCI_OK) then
      vci_open_output = stat; return
    end if
    nc = 0
    if (.not. c_associated(path)) then
      stat = fail(ip, VCI_ERR_ARGUMENT, 'vci_open_output: path is NULL')
    else
      nc = int(min(c_strlen(path), int(huge(1), c_size_t)))
      if (nc == 0) stat = fail(ip, VCI_ERR_ARGUMENT, 'vci_open_output: path is empty')
    end if
    if (stat == VCI_OK) then
      call c_f_pointer(path, chars, [nc])
      allocate (character(len=nc) :: fpath)
      do i = 1, nc
        fpath(i:i) = chars(i)
      end do
      stat = close_output(ip)
      if (stat /= VCI_OK) stat = fail(ip, stat, 'vci_open_output: the previous output file could not be finished')
    end if
    if (stat == VCI_OK) then
#ifdef VCI_HAVE_HDF5
      block
        type(vci_hdf5_writer_t), allocatable :: w
        allocate (w, stat=stat)
        if (stat /= 0) then
          stat = fail(ip, VCI_ERR_MEMORY, 'vci_open_output: out of memory')
        else
          call lock_io()
          call w%open(fpath, stat, overwrite=.true.)
          call unlock_io()
          if (stat /= VCI_OK) then
            stat = fail(ip, VCI_ERR_IO, 'vci_open_output: '//trim(w%message))
          else
            call move_alloc(w, ip%obs%output)
            ip%obs%started = .false.
            ip%obs%direction = 0
          end if
        end if
      end block
#else
      stat = fail(ip, VCI_ERR_IO, 'vci_open_output: cannot write '//fpath// &
                  ': this vci library was built without HDF5 (configure with -DVCI_WITH_HDF5=ON)')
#endif
    end if
    call leave(ip)
    vci_open_output = stat
  end function vci_open_output

  !> int vci_close_output(vci_integrator integ): finish and close the output file (no-op without one).
  integer(c_int) function vci_close_output(integ) bind(C, name='vci_close_output')
    type(c_ptr), value :: integ
    type(c_integrator_t), pointer :: ip
    integer :: stat
    character(len=VCI_MSG_LEN) :: why
    call enter(integ, 'vci_close_output', ip, stat)
    if (stat == VCI_OK) then
      why = output_message(ip)
      stat = close_output(ip)
      if (stat /= VCI_OK) stat = fail(ip, stat, 'vci_close_output: the output file could not be finished: '//trim(why))
      call leave(ip)
    end if
    vci_close_output = stat
  end function vci_close_output

  !> int vci_last_error(vci_integrator integ, char *buffer, int size): the message of the last
  !> call on integ (empty after success), or with integ == NULL the calling thread's last failure
  !> that had no live integrator to hold it. Truncated to size - 1 characters and NUL-terminated.
  integer(c_int) function vci_last_error(integ, buffer, size) bind(C, name='vci_last_error')
    type(c_ptr), value :: integ, buffer
    integer(c_int), value :: size
    character(kind=c_char), pointer :: out(:)
    character(len=VCI_MSG_LEN) :: msg
    integer :: i, nc
    if (.not. c_associated(buffer) .or. size < 1) then
      vci_last_error = VCI_ERR_ARGUMENT; return
    end if
    vci_last_error = VCI_OK
    if (.not. c_associated(integ)) then
      msg = thread_message()
    else
      ! under the lock: no call on it can start (and write its message) while it is copied
      call lock_registry()
      i = find_live(integ, KIND_INTEGRATOR)
      if (i == 0) then
        msg = 'vci_last_error: not a live integrator handle (destroyed, or not made by vci_integrator_create)'
        vci_last_error = VCI_ERR_ARGUMENT
      else if (slots(i)%integ%busy) then
        msg = 'vci_last_error: the integrator is busy (a call on it is running)'
        vci_last_error = VCI_ERR_STATE
      else
        msg = slots(i)%integ%integ%message_text()
      end if
      call unlock_registry()
    end if
    call c_f_pointer(buffer, out, [size])
    nc = min(len_trim(msg), size - 1)
    do i = 1, nc
      out(i) = msg(i:i)
    end do
    out(nc + 1) = c_null_char
  end function vci_last_error

  !> const char *vci_status_string(int status): a static, NUL-terminated description.
  type(c_ptr) function vci_status_string(status) bind(C, name='vci_status_string')
    integer(c_int), value :: status
    integer :: i
    i = N_STATUS + 1    ! 'unknown status'
    if (status >= 0 .and. status <= N_STATUS) i = int(status)
    vci_status_string = c_loc(status_text(i))
  end function vci_status_string

  !> int vci_version(void): major*10000 + minor*100 + patch.
  integer(c_int) function vci_version() bind(C, name='vci_version')
    vci_version = VCI_VERSION_NUMBER
  end function vci_version
end module vci_capi
