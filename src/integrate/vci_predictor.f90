!> Newton's start for a regular step, extrapolated from the state's history (docs/DESIGN.md §4).
module vci_predictor
  use vci_kinds, only: dp
  use vci_scheme, only: vci_scheme_t
  use vci_state, only: vci_state_t
  implicit none
  private
  public :: vci_predict_start

contains

  !> Newton's start x for the regular step of direction dir from state: after `depth` consecutive
  !> regular steps the configuration and multipliers are extrapolated from the last ones (q
  !> quadratic from depth 2: 3 q_k - 3 q_{k-1} + q_{k-2}; lambda linear at depth 2, quadratic at 3);
  !> before, q + h v and the last multipliers (placed by the scheme: put_multiplier_history). Exact
  !> for the quadratic free flight of uniform
  !> gravity (no iteration then), else O(h^3) from the solution. Schemes with interior stages
  !> (Lobatto) place every stage on that quadratic (put_quadratic_start): on the chord to the
  !> guessed endpoint the interior stages would start O(h^2) off. q_guess (n) and lambda_start (m)
  !> are workspace.
  subroutine vci_predict_start(sys, state, dir, depth, x, q_guess, lambda_start)
    class(vci_scheme_t), intent(inout) :: sys
    type(vci_state_t), intent(in) :: state
    integer, intent(in) :: dir, depth
    real(dp), intent(inout) :: x(:), q_guess(:), lambda_start(:)
    real(dp) :: h
    h = state%h
    if (depth >= 2 .and. sys%needs_pair_solve()) then
      call sys%put_quadratic_start(x, state%q, real(dir, dp) * h, state%velocity, state%velocity_before)
    else
      if (depth >= 2) then
        q_guess(:) = state%q + real(dir, dp) * h * (2.0_dp * state%velocity - state%velocity_before)
      else
        q_guess(:) = state%q + real(dir, dp) * h * state%velocity
      end if
      call sys%put_endpoint(x, state%q, q_guess)
    end if
    if (sys%m == 0) then
      call sys%put_multipliers(x, state%lambda)
    else
      call sys%put_multiplier_history(x, depth, state%lambda, state%lambda_before, state%lambda_before2, &
                                      lambda_start)
    end if
  end subroutine vci_predict_start
end module vci_predictor
