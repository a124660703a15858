!> The "Long steps" table of docs/STABILITY.md (issue 27): per scene and scheme, the largest step
!> of a ladder that runs to the end with no failure status (every shorter one too) without walls
!> (the free flight), with
!> walls and the safety net off, and with walls and the net on (default bound 16), with the error
!> against the reference there and the steps the net took. Same runners as test_stab_long_steps
!> (test/stability/vci_long_cases.f90). The last column: the largest h up to which every run with the
!> net on ends within 0.1 of the reference (a run with status 0 can be far off: read the errors).
!> `vci_long_steps_table -v` also prints every run (status, error, |H - H0| for the Kepler scenes,
!> impacts against the reference's, steps split); a scene number (1 ... LONG_SCENES) runs only that
!> scene's rows: `vci_long_steps_table -v 6`.
program vci_long_steps_table
  use vci
  use vci_long_cases
  implicit none
  integer, parameter :: n_h = 9, n_schemes = 4
  real(dp), parameter :: ladders(n_h, LONG_SCENES) = reshape([ &
    0.05_dp, 0.1_dp, 0.2_dp, 0.3_dp, 0.4_dp, 0.5_dp, 0.6_dp, 0.8_dp, 1.0_dp, &
    0.05_dp, 0.1_dp, 0.2_dp, 0.3_dp, 0.4_dp, 0.5_dp, 0.6_dp, 0.8_dp, 1.0_dp, &
    0.02_dp, 0.05_dp, 0.1_dp, 0.15_dp, 0.2_dp, 0.25_dp, 0.3_dp, 0.4_dp, 0.5_dp, &
    0.05_dp, 0.1_dp, 0.2_dp, 0.3_dp, 0.4_dp, 0.5_dp, 0.6_dp, 0.8_dp, 1.0_dp, &
    0.5_dp, 1.0_dp, 1.5_dp, 2.0_dp, 2.5_dp, 3.0_dp, 3.5_dp, 4.0_dp, 5.0_dp, &
    0.05_dp, 0.1_dp, 0.2_dp, 0.3_dp, 0.4_dp, 0.5_dp, 0.6_dp, 0.8_dp, 1.0_dp], [n_h, LONG_SCENES])
  integer, parameter :: schemes(n_schemes) = [VCI_SCHEME_MIDPOINT, VCI_SCHEME_LOBATTO, VCI_SCHEME_LOBATTO, &
                                              VCI_SCHEME_LOBATTO]
  integer, parameter :: stages(n_schemes) = [1, 2, 3, 4]
  character(len=12), parameter :: scheme_label(n_schemes) = [character(len=12) :: 'midpoint', 'lobatto s=2', &
                                                               'lobatto s=3', 'lobatto s=4']
  type(long_run_t) :: r
  real(dp), parameter :: accurate = 0.1_dp   ! the last column: error below this at every h up to it
  integer :: scene, is, ih, mode, best(3), best_acc, only, iarg, ios
  real(dp) :: err(3)
  integer(i8) :: splits
  logical :: verbose, going(3)
  character(len=32) :: arg
  verbose = .false.; only = 0
  do iarg = 1, command_argument_count()
    call get_command_argument(iarg, arg)
    if (arg == '-v') then
      verbose = .true.
    else
      read (arg, *, iostat=ios) only
      if (ios /= 0 .or. only < 1 .or. only > LONG_SCENES) then
        write (*, '(a)') 'usage: vci_long_steps_table [-v] [scene 1 ... 6]'
        stop 2
      end if
    end if
  end do
  write (*, '(a)') '| scene | scheme | free flight: largest h (error) | walls, net off: largest h (error) '// &
    '| walls, net on: largest h (error, steps split / most sub-steps) | walls, net on: largest h with error < 0.1 |'
  write (*, '(a)') '|---|---|---|---|---|---|'
  do scene = 1, LONG_SCENES
    if (only > 0 .and. scene /= only) cycle
    do is = 1, n_schemes
      best = 0; err = huge(1.0_dp); going = .true.; splits = 0; best_acc = 0
      do ih = 1, n_h
        do mode = 1, 3
          if (.not. going(mode)) cycle
          select case (mode)
          case (1); call long_run(scene, schemes(is), stages(is), ladders(ih, scene), 1, r, walls=.false.)
          case (2); call long_run(scene, schemes(is), stages(is), ladders(ih, scene), 1, r)
          case (3); call long_run(scene, schemes(is), stages(is), ladders(ih, scene), 16, r)
          end select
          if (verbose) write (*, '(a,a,a,f5.2,a,i0,a,i0,a,es9.2,a,es9.2,a,i0,a,i0,a,i0,a,i0,a,a)') trim(long_scene_name(scene)), &
            ' ', scheme_label(is), ladders(ih, scene), ' mode ', mode, ' status ', r%status, ' error ', r%error, &
            ' |H - H0| ', r%energy_error, ' impacts ', r%impacts, ' exact ', r%exact_impacts, ' split ', &
            r%split_steps, ' / ', r%largest_split, ' ', &
            trim(r%message(1:200))
          ! runs: to the end with no failure status (the error says how good the motion is there)
          if (r%status == VCI_OK .and. r%error < huge(1.0_dp)) then
            best(mode) = ih; err(mode) = r%error
            if (mode == 3) splits = r%split_steps * 1000 + r%largest_split
            if (mode == 3 .and. best_acc == ih - 1 .and. r%error < accurate) best_acc = ih
          else
            going(mode) = .false.
          end if
        end do
      end do
      write (*, '(6a)') '| ', trim(long_scene_name(scene)), ' | ', trim(scheme_label(is)), ' | ', &
        trim(cell(best(1), err(1), scene))//' | '//trim(cell(best(2), err(2), scene))//' | '// &
        trim(cell(best(3), err(3), scene))//trim(split_text(best(3), splits))//' | '//trim(acc_cell(best_acc, scene))//' |'
    end do
  end do
contains
  function cell(ih, e, scene) result(text)
    integer, intent(in) :: ih, scene
    real(dp), intent(in) :: e
    character(len=40) :: text
    if (ih == 0) then
      text = 'none of the ladder'
    else
      write (text, '(f0.2,a,es8.1,a)') ladders(ih, scene), ' (', e, ')'
      if (text(1:1) == '.') text = '0'//trim(text)
      if (ih == n_h) text = trim(text)//', the whole ladder'
    end if
  end function cell

  function acc_cell(ih, scene) result(text)
    integer, intent(in) :: ih, scene
    character(len=24) :: text
    if (ih == 0) then
      text = 'none'
    else
      write (text, '(f0.2)') ladders(ih, scene)
      if (text(1:1) == '.') text = '0'//text(1:len(text) - 1)
    end if
  end function acc_cell

  function split_text(ih, code) result(text)
    integer, intent(in) :: ih
    integer(i8), intent(in) :: code
    character(len=40) :: text
    text = ''
    if (ih == 0) return
    write (text, '(a,i0,a,i0)') '; split ', code / 1000, ' / ', mod(code, 1000_i8)
  end function split_text
end program vci_long_steps_table
