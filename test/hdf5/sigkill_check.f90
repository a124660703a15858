!> Checks a pendulum file left by a run killed with SIGKILL (sigkill.sh): it opens, says the run was
!> not closed, holds at least the steps of the last flush (steps_completed, written last at each flush)
!> in every dataset, every flushed row equals a fresh in-process run bit for bit, and its
!> /checkpoint is the state of the row it names. Then it restarts from the file, appends, and checks
!> the continuation against the reference run too. Usage: hdf5_sigkill_check FILE H MIN_FLUSHED
!> (MIN_FLUSHED: the steps the writer must have flushed before the kill, sigkill.sh says why).
program sigkill_check
  use hdf5, only: hid_t
  use vci
  use vci_hdf5_output, only: VCI_HDF5_RUNNING, vci_hdf5_writer_t, vci_hdf5_read_checkpoint
  use vci_scene_pendulum, only: pendulum_t, pendulum_model
  use h5_test_support
  implicit none
  character(len=512) :: path, arg
  integer(hid_t) :: f
  integer(i8) :: flushed, min_flushed
  integer :: rows, steps, stat, s, r, total, ios
  type(vci_checkpoint_t) :: cp
  type(vci_integrator_t), target :: integ2
  type(vci_hdf5_writer_t), target :: w
  character(len=VCI_MSG_LEN) :: msg
  real(dp) :: h, q0(2), qd(2), pi
  real(dp), allocatable :: t(:), q(:, :), p(:, :), e(:), l(:, :), cq(:)
  type(pendulum_t), target :: model
  type(vci_integrator_t) :: integ
  type(tape_t) :: tape

  if (command_argument_count() /= 3) call die('usage: hdf5_sigkill_check FILE H MIN_FLUSHED')
  call get_command_argument(1, path)
  call get_command_argument(2, arg)
  read (arg, *, iostat=ios) h
  if (ios /= 0) call die('H is not a number: '//trim(arg))
  call get_command_argument(3, arg)
  read (arg, *, iostat=ios) min_flushed
  if (ios /= 0) call die('MIN_FLUSHED is not an integer: '//trim(arg))
  f = h5r_open(trim(path))
  if (f < 0) call die('the file does not open')
  if (h5r_attr_int(f, 'status') /= VCI_HDF5_RUNNING) call die('status should still say "running"')
  flushed = h5r_attr_i8(f, 'steps_completed')
  t = h5r_real1(f, 't'); q = h5r_real2(f, 'q'); p = h5r_real2(f, 'p')
  e = h5r_real1(f, 'energy'); l = h5r_real2(f, 'lambda')
  rows = size(t); steps = size(e)
  write (*, '(a,i0,a,i0,a,i0)') 'steps_completed ', flushed, '  rows of /t ', rows, '  rows of /energy ', steps
  ! the run reported N steps done before the kill; the writer flushes whenever flush_every rows
  ! are buffered, so at least N - flush_every + 1 of them are on disk
  if (flushed < max(min_flushed, 1000_i8)) then
    write (arg, '(i0,a,i0)') flushed, ' < ', max(min_flushed, 1000_i8)
    call die('steps_completed '//trim(arg)//': steps the run had done before the kill were not flushed')
  end if
  ! a kill inside a flush may leave some datasets longer than others beyond the flushed rows (each
  ! dataset's new extent reaches the disk on its own): only the flushed rows must be in all of them
  if (min(rows, size(q, 2), size(p, 2)) < flushed + 1 .or. min(steps, size(l, 2)) < flushed) &
    call die('a dataset holds fewer rows than the flushed steps')
  s = int(flushed)   ! rows beyond the flushed ones (a kill during a flush) are not checked
  cq = h5r_real1(f, 'checkpoint/record')   ! [row, k, t0, h, energy, e_arrive, e_dir, q(2), ...]
  r = nint(cq(1)) + 1
  cq = cq(8:9)
  if (r < 1 .or. r > min(rows, size(q, 2))) call die('/checkpoint names a row outside /t or /q')
  if (any(cq /= q(:, r))) call die('/checkpoint is not the state of the row it names')

  ! the restart point: the checkpoint, which a kill inside a flush may leave one flush interval
  ! ahead of steps_completed (its record is written before the count); the reference run and the
  ! continued file reach `total` steps, 500 beyond the later of the two
  call vci_hdf5_read_checkpoint(trim(path), cp, stat, msg)
  if (stat /= VCI_OK) call die('read_checkpoint: '//trim(msg))
  total = max(s, int(cp%step) - 1) + 500

  ! the same run in-process: the file's rows must be its first states bit for bit
  pi = acos(-1.0_dp)
  q0 = [0.75_dp * pi, 0.0_dp]
  qd = [pi / 4.0_dp, (pi + 0.5_dp) * pi / 4.0_dp]
  model = pendulum_model()
  call integ%create(model, h, stat)
  call integ%init_from_pair(0.0_dp, q0, q0 + h * qd, stat)
  call integ%integrate(int(total, i8), 1, stat, tape)
  if (stat /= VCI_OK) call die('reference run failed: '//integ%message())
  if (any(tape%t(1:s + 1) /= t(1:s + 1))) call die('/t differs from the reference run')
  if (any(tape%q(:, 1:s + 1) /= q(:, 1:s + 1)) .or. any(tape%p(:, 1:s + 1) /= p(:, 1:s + 1))) &
    call die('/q or /p differs from the reference run')
  if (any(tape%e(1:s) /= e(1:s)) .or. any(tape%l(:, 1:s) /= l(:, 1:s))) &
    call die('/energy or /lambda differs from the reference run')
  call h5r_close(f)
  write (*, '(a,i0,a)') 'ok: ', s, ' flushed steps on disk, identical to the reference run'

  ! restart from the killed file, append up to `total` steps: the file then matches the reference run
  call integ2%create(model, h, stat)
  call integ2%restore(cp, stat)
  if (stat /= VCI_OK) call die('restore: '//trim(integ2%message()))
  call w%open(trim(path), stat, append=.true.)
  if (stat /= VCI_OK) call die('append: '//trim(w%message))
  call integ2%integrate(int(total, i8) - (cp%step - 1), 1, stat, w)
  if (stat /= VCI_OK) call die('restarted run: '//trim(integ2%message()))
  f = h5r_open(trim(path))
  t = h5r_real1(f, 't'); q = h5r_real2(f, 'q'); e = h5r_real1(f, 'energy')
  if (size(t) /= total + 1) call die('the continued file does not have the expected rows')
  if (h5r_attr_int(f, 'status') /= VCI_OK) call die('the continued file''s status is not ok')
  if (any(tape%t /= t) .or. any(tape%q /= q) .or. any(tape%e /= e)) &
    call die('the continued file differs from the reference run')
  if (any(tape%it /= h5r_real1(f, 'impacts/time'))) call die('/impacts/time differs from the reference run')
  call h5r_close(f)
  write (*, '(a)') 'ok: restarted and appended; identical to the reference run bit for bit'
contains
  subroutine die(msg)
    character(len=*), intent(in) :: msg
    write (*, '(a)') 'FAIL: '//msg
    error stop 1
  end subroutine die
end program sigkill_check
