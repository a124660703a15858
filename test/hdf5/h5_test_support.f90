!> Test support for the HDF5 output: a reader written directly against HDF5's Fortran API
!> (independent of the writer's own helpers), an observer that records a run and forwards it,
!> a model without walls and one whose callback fails at a chosen time.
module h5_test_support
  use hdf5
  use vci
  use vci_scene_particle, only: particle_t
  implicit none
  private

  public :: h5r_open, h5r_close, h5r_exists, h5r_shape, h5r_real1, h5r_real2, h5r_i8_1, h5r_int1
  public :: h5r_attr_real, h5r_attr_int, h5r_attr_i8, h5r_attr_str, h5r_num_attrs
  public :: free_fall_model, failing_fall_model

  !> Records everything an observer sees and passes it on to `next` (the writer under test).
  type, extends(vci_observer_t), public :: tape_t
    class(vci_observer_t), pointer :: next => null()
    type(vci_run_info_t) :: info
    integer :: ns = 0, ne = 0, ni = 0
    real(dp), allocatable :: t(:), q(:, :), p(:, :), e(:), l(:, :)
    real(dp), allocatable :: it(:), ia(:), iq(:, :), ii(:)
    integer(i8), allocatable :: irow(:)
    integer, allocatable :: ig(:)
    integer :: status = -99
    character(len=:), allocatable :: message
  contains
    procedure :: on_start => tape_start
    procedure :: on_step => tape_step
    procedure :: on_impact => tape_impact
    procedure :: on_finish => tape_finish
  end type tape_t

  !> Free fall in the plane, no walls, no constraints: n = 2, m = 0, n_gaps = 0. With fail_below set,
  !> d1 reports failure once y drops below it (a callback error in mid-run).
  type, extends(particle_t), public :: fall_t
    real(dp) :: fail_below = -huge(1.0_dp)
  contains
    procedure :: d1 => fall_d1
  end type fall_t

contains

  function free_fall_model() result(model)
    type(fall_t) :: model
    model%n = 2; model%m = 0; model%n_gaps = 0
    model%mass = 1.0_dp; model%grav = 9.8_dp
  end function free_fall_model

  function failing_fall_model(y_fail) result(model)
    real(dp), intent(in) :: y_fail
    type(fall_t) :: model
    model = free_fall_model()
    model%fail_below = y_fail
  end function failing_fall_model

  subroutine fall_d1(self, q, v, h, out, stat)
    class(fall_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    call self%particle_t%d1(q, v, h, out, stat)
    if (q(2) < self%fail_below) stat = 1
  end subroutine fall_d1

  ! ---- the recording observer ----

  subroutine tape_start(self, info, q, p, stat)
    class(tape_t), intent(inout) :: self
    type(vci_run_info_t), intent(in) :: info
    real(dp), intent(in) :: q(:), p(:)
    integer, intent(inout) :: stat
    integer, parameter :: c = 1024
    self%info = info
    self%ns = 0; self%ne = 0; self%ni = 0
    allocate (self%t(c), self%q(info%n, c), self%p(info%n, c), self%e(c), self%l(info%m, c))
    allocate (self%it(c), self%ia(c), self%iq(info%n, c), self%ii(c), self%irow(c), self%ig(c))
    call add_state(self, info%t0, q, p)
    if (associated(self%next)) call self%next%on_start(info, q, p, stat)
  end subroutine tape_start

  subroutine add_state(self, t, q, p)
    type(tape_t), intent(inout) :: self
    real(dp), intent(in) :: t, q(:), p(:)
    if (self%ns == size(self%t)) then   ! double the capacity of the state and step arrays
      call grow1(self%t); call grow2(self%q); call grow2(self%p); call grow1(self%e); call grow2(self%l)
    end if
    self%ns = self%ns + 1
    self%t(self%ns) = t; self%q(:, self%ns) = q; self%p(:, self%ns) = p
  end subroutine add_state

  subroutine grow1(x)
    real(dp), allocatable, intent(inout) :: x(:)
    real(dp), allocatable :: y(:)
    allocate (y(2 * size(x))); y(1:size(x)) = x; call move_alloc(y, x)
  end subroutine grow1

  subroutine grow2(x)
    real(dp), allocatable, intent(inout) :: x(:, :)
    real(dp), allocatable :: y(:, :)
    allocate (y(size(x, 1), 2 * size(x, 2))); y(:, 1:size(x, 2)) = x; call move_alloc(y, x)
  end subroutine grow2

  subroutine tape_step(self, step, t, q, p, lambda, energy, stat)
    class(tape_t), intent(inout) :: self
    integer(i8), intent(in) :: step
    real(dp), intent(in) :: t, q(:), p(:), lambda(:), energy
    integer, intent(inout) :: stat
    call add_state(self, t, q, p)
    self%ne = self%ne + 1
    self%e(self%ne) = energy
    self%l(:, self%ne) = lambda
    if (associated(self%next)) call self%next%on_step(step, t, q, p, lambda, energy, stat)
  end subroutine tape_step

  subroutine tape_impact(self, impact, stat)
    class(tape_t), intent(inout) :: self
    type(vci_impact_t), intent(in) :: impact
    integer, intent(inout) :: stat
    integer :: k
    k = self%ni + 1
    if (k > size(self%it)) call die_tape('more than 1024 impacts: enlarge the tape')
    self%it(k) = impact%t; self%ia(k) = impact%alpha; self%ii(k) = impact%impulse
    self%ig(k) = impact%gap; self%iq(:, k) = impact%q
    self%irow(k) = (impact%step - self%info%step0) * self%info%direction
    self%ni = k
    if (associated(self%next)) call self%next%on_impact(impact, stat)
  end subroutine tape_impact

  subroutine die_tape(msg)
    character(len=*), intent(in) :: msg
    error stop msg
  end subroutine die_tape

  !> Trims the arrays to what was recorded, so tests compare whole arrays.
  subroutine tape_finish(self, status, message, stat)
    class(tape_t), intent(inout) :: self
    integer, intent(in) :: status
    character(len=*), intent(in) :: message
    integer, intent(inout) :: stat
    self%status = status
    self%message = message
    self%t = self%t(1:self%ns); self%q = self%q(:, 1:self%ns); self%p = self%p(:, 1:self%ns)
    self%e = self%e(1:self%ne); self%l = self%l(:, 1:self%ne)
    self%it = self%it(1:self%ni); self%ia = self%ia(1:self%ni); self%ii = self%ii(1:self%ni)
    self%ig = self%ig(1:self%ni); self%iq = self%iq(:, 1:self%ni); self%irow = self%irow(1:self%ni)
    if (associated(self%next)) call self%next%on_finish(status, message, stat)
  end subroutine tape_finish

  ! ---- the reader ----

  !> Open read-only; fid < 0 when the file cannot be opened.
  integer(hid_t) function h5r_open(path) result(fid)
    character(len=*), intent(in) :: path
    integer :: err
    call h5open_f(err)
    call h5eset_auto_f(0, err)
    call h5fopen_f(path, H5F_ACC_RDONLY_F, fid, err)
    if (err /= 0) fid = -1
  end function h5r_open

  subroutine h5r_close(fid)
    integer(hid_t), intent(inout) :: fid
    integer :: err
    if (fid >= 0) call h5fclose_f(fid, err)
    fid = -1
  end subroutine h5r_close

  !> Does the path (e.g. 'impacts/time') exist? Checks each level.
  logical function h5r_exists(fid, name)
    integer(hid_t), intent(in) :: fid
    character(len=*), intent(in) :: name
    integer :: err, k
    h5r_exists = .true.
    k = index(name, '/')
    if (k > 0) then
      call h5lexists_f(fid, name(1:k - 1), h5r_exists, err)
      if (.not. h5r_exists) return
    end if
    call h5lexists_f(fid, name, h5r_exists, err)
    if (err /= 0) h5r_exists = .false.
  end function h5r_exists

  !> The dataset's shape as h5py shows it (C order: rows first).
  function h5r_shape(fid, name) result(shape_c)
    integer(hid_t), intent(in) :: fid
    character(len=*), intent(in) :: name
    integer, allocatable :: shape_c(:)
    integer(hid_t) :: d, s
    integer(hsize_t) :: dims(7), maxd(7)
    integer :: rank, err
    call h5dopen_f(fid, name, d, err)
    call h5dget_space_f(d, s, err)
    call h5sget_simple_extent_ndims_f(s, rank, err)
    call h5sget_simple_extent_dims_f(s, dims(1:rank), maxd(1:rank), err)
    shape_c = int(dims(rank:1:-1))
    call h5sclose_f(s, err); call h5dclose_f(d, err)
  end function h5r_shape

  function h5r_real1(fid, name) result(x)
    integer(hid_t), intent(in) :: fid
    character(len=*), intent(in) :: name
    real(dp), allocatable :: x(:)
    integer, allocatable :: sh(:)
    integer(hid_t) :: d
    integer :: err
    sh = h5r_shape(fid, name)
    allocate (x(sh(1)))
    call h5dopen_f(fid, name, d, err)
    call h5dread_f(d, H5T_NATIVE_DOUBLE, x, [int(sh(1), hsize_t)], err)
    call h5dclose_f(d, err)
  end function h5r_real1

  !> A 2-D dataset of h5py shape (rows, width) as x(width, rows).
  function h5r_real2(fid, name) result(x)
    integer(hid_t), intent(in) :: fid
    character(len=*), intent(in) :: name
    real(dp), allocatable :: x(:, :)
    integer, allocatable :: sh(:)
    integer(hid_t) :: d
    integer :: err
    sh = h5r_shape(fid, name)
    allocate (x(sh(2), sh(1)))
    call h5dopen_f(fid, name, d, err)
    call h5dread_f(d, H5T_NATIVE_DOUBLE, x, [int(sh(2), hsize_t), int(sh(1), hsize_t)], err)
    call h5dclose_f(d, err)
  end function h5r_real2

  function h5r_i8_1(fid, name) result(x)
    integer(hid_t), intent(in) :: fid
    character(len=*), intent(in) :: name
    integer(i8), allocatable :: x(:)
    integer, allocatable :: sh(:)
    integer(hid_t) :: d
    integer :: err
    sh = h5r_shape(fid, name)
    allocate (x(sh(1)))
    call h5dopen_f(fid, name, d, err)
    call h5dread_f(d, h5kind_to_type(i8, H5_INTEGER_KIND), x, [int(sh(1), hsize_t)], err)
    call h5dclose_f(d, err)
  end function h5r_i8_1

  function h5r_int1(fid, name) result(x)
    integer(hid_t), intent(in) :: fid
    character(len=*), intent(in) :: name
    integer, allocatable :: x(:)
    integer, allocatable :: sh(:)
    integer(hid_t) :: d
    integer :: err
    sh = h5r_shape(fid, name)
    allocate (x(sh(1)))
    call h5dopen_f(fid, name, d, err)
    call h5dread_f(d, H5T_NATIVE_INTEGER, x, [int(sh(1), hsize_t)], err)
    call h5dclose_f(d, err)
  end function h5r_int1

  real(dp) function h5r_attr_real(fid, name) result(v)
    integer(hid_t), intent(in) :: fid
    character(len=*), intent(in) :: name
    integer(hid_t) :: a
    integer :: err
    v = -huge(1.0_dp)
    call open_attr(fid, name, a, err)
    if (err /= 0) return
    call h5aread_f(a, H5T_NATIVE_DOUBLE, v, [1_hsize_t], err)
    call h5aclose_f(a, err)
  end function h5r_attr_real

  integer function h5r_attr_int(fid, name) result(v)
    integer(hid_t), intent(in) :: fid
    character(len=*), intent(in) :: name
    integer(hid_t) :: a
    integer :: err
    v = -huge(1)
    call open_attr(fid, name, a, err)
    if (err /= 0) return
    call h5aread_f(a, H5T_NATIVE_INTEGER, v, [1_hsize_t], err)
    call h5aclose_f(a, err)
  end function h5r_attr_int

  integer(i8) function h5r_attr_i8(fid, name) result(v)
    integer(hid_t), intent(in) :: fid
    character(len=*), intent(in) :: name
    integer(hid_t) :: a
    integer :: err
    v = -huge(1_i8)
    call open_attr(fid, name, a, err)
    if (err /= 0) return
    call h5aread_f(a, h5kind_to_type(i8, H5_INTEGER_KIND), v, [1_hsize_t], err)
    call h5aclose_f(a, err)
  end function h5r_attr_i8

  !> A string attribute without its null padding; '<missing>' when absent.
  function h5r_attr_str(fid, name) result(v)
    integer(hid_t), intent(in) :: fid
    character(len=*), intent(in) :: name
    character(len=:), allocatable :: v
    integer(hid_t) :: a, t
    integer(size_t) :: sz
    integer :: err, k
    v = '<missing>'
    call open_attr(fid, name, a, err)
    if (err /= 0) return
    call h5aget_type_f(a, t, err)
    call h5tget_size_f(t, sz, err)
    deallocate (v); allocate (character(len=sz) :: v)
    call h5aread_f(a, t, v, [1_hsize_t], err)
    call h5tclose_f(t, err); call h5aclose_f(a, err)
    k = index(v, achar(0))
    if (k > 0) v = v(1:k - 1)
  end function h5r_attr_str

  !> Open an attribute given as 'name' (of the root) or 'group/name'.
  subroutine open_attr(fid, name, a, err)
    integer(hid_t), intent(in) :: fid
    character(len=*), intent(in) :: name
    integer(hid_t), intent(out) :: a
    integer, intent(out) :: err
    integer :: k
    k = index(name, '/', back=.true.)
    if (k > 0) then
      call h5aopen_by_name_f(fid, name(1:k - 1), name(k + 1:), a, err)
    else
      call h5aopen_f(fid, name, a, err)
    end if
  end subroutine open_attr

  !> Number of attributes on an object (the root: '/').
  integer function h5r_num_attrs(fid, name) result(na)
    integer(hid_t), intent(in) :: fid
    character(len=*), intent(in) :: name
    integer(hid_t) :: o
    integer :: err
    type(h5o_info_t) :: info
    call h5oopen_f(fid, name, o, err)
    call h5oget_info_f(o, info, err)
    na = int(info%num_attrs)
    call h5oclose_f(o, err)
  end function h5r_num_attrs
end module h5_test_support
