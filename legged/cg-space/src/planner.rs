//! Route and footfalls together, with the foot-level search's feedback to the route
//! planner: a CG cell the search cannot get past is marked invalid and the route replanned,
//! the footfalls planned so far along the route's unchanged beginning kept.

use nalgebra::Point2;
use serde::{Deserialize, Serialize};

use crate::distribute::{BatchParams, BatchedRouteError, Joiner, plan_route_batched};
use crate::error::CgError;
use crate::footplan::{
    FootCell, FootPlan, FootSearch, FootStep, MoveCheck, SearchCounts, SearchFailure, SearchParams,
    Stance, apply, millimetres,
};
use crate::grid::CgCell;
use crate::route::{Route, RouteParams, plan_route};
use crate::space::CgSpace;

/// Everything the planner is given besides the space.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanParams {
    /// Route planning.
    pub route: RouteParams,
    /// The foot-level search.
    pub search: SearchParams,
    /// Routes replanned after a search that got no nearer the goal than an earlier one
    /// before the planner gives up. A search that sticks nearer the goal (in cell steps
    /// from the furthest cell it reached) than any before it is progress and does not
    /// count, but no plan replans more than four times this in all.
    pub max_replans: usize,
    /// Cells around a cell the search cannot get past that are marked with it (same
    /// heading, within this many cells in x and y): 0 marks the cell alone, as the paper's
    /// feedback would; more moves the next route further from where the search stuck.
    pub mark_radius: i32,
    /// Route cells the planner backs off from the furthest cell a failed search reached
    /// before it plans the rest again: the stance that reached that cell is the one the
    /// search could not get on from, so the next search starts this many cells earlier
    /// (never before where the failed search started), with room to set its feet for the
    /// new way. 0 goes on from the furthest stance itself.
    #[serde(default)]
    pub backoff_cells: usize,
    /// How near the goal the CG must come, metres: 0 asks for the goal's own cell. Above 0,
    /// a search that sticks once the CG stands on a route cell whose centre is this near the
    /// goal has arrived: the plan ends there (its moves put to the outside check first)
    /// instead of marking cells round the goal and replanning. Where the goal's own cell is
    /// invalid, the plan heads for the valid cell nearest the goal within this distance.
    #[serde(default)]
    pub goal_tolerance_m: f64,
}

impl Default for PlanParams {
    fn default() -> Self {
        PlanParams {
            route: RouteParams::default(),
            search: SearchParams::default(),
            max_replans: 60,
            mark_radius: 2,
            backoff_cells: 0,
            goal_tolerance_m: 0.0,
        }
    }
}

/// A planned walk: the route and the foot moves along it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// The final route (its cells) and the foot moves.
    pub feet: FootPlan,
    /// The first route's statistics.
    pub first_route: Route,
    /// Cells marked invalid by the feedback, in order.
    pub marked: Vec<CgCell>,
    /// Routes planned in all.
    pub routes: usize,
    /// What the foot-level searches counted, over every route.
    pub counts: SearchCounts,
}

/// Where the robot stands when a plan starts.
#[derive(Debug, Clone, PartialEq)]
pub struct Standing {
    /// Each foot's world X, Y (`None` for a foot in the air).
    pub feet: Vec<Option<Point2<f64>>>,
    /// World Z of the body origin, metres.
    pub body_z: f64,
}

/// Plans from a start pose to a goal pose. `standing` is where each foot stands at the
/// start and how high the body is; without it, a stance is chosen.
pub fn plan(
    space: &mut CgSpace,
    start: (Point2<f64>, f64),
    goal: (Point2<f64>, f64),
    standing: Option<&Standing>,
    params: &PlanParams,
) -> Result<Plan, CgError> {
    plan_checked(space, start, goal, standing, params, None)
}

/// Where the planner's routes come from: the first one and each one after the feedback
/// marked a cell.
pub trait RoutePlanner {
    /// A route from `start` to `goal` over the valid cells of `space` (the marked ones
    /// included among the invalid).
    fn route(
        &mut self,
        space: &mut CgSpace,
        start: CgCell,
        goal: CgCell,
        params: &RouteParams,
    ) -> Result<Route, CgError>;
}

/// Routes planned in the planner's own space by [`plan_route`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LocalRoutes;

impl RoutePlanner for LocalRoutes {
    fn route(
        &mut self,
        space: &mut CgSpace,
        start: CgCell,
        goal: CgCell,
        params: &RouteParams,
    ) -> Result<Route, CgError> {
        plan_route(space, start, goal, params)
    }
}

/// Routes planned by [`plan_route_batched`], the roadmap's joins run by a [`Joiner`] (on
/// workers, for one): the cells the feedback marks travel with every batch.
#[derive(Debug)]
pub struct JoinedRoutes<J> {
    /// Runs the roadmap's joins.
    pub joiner: J,
    /// How the roadmap draws its points.
    pub batch: BatchParams,
}

impl<J: Joiner> RoutePlanner for JoinedRoutes<J> {
    fn route(
        &mut self,
        space: &mut CgSpace,
        start: CgCell,
        goal: CgCell,
        params: &RouteParams,
    ) -> Result<Route, CgError> {
        plan_route_batched(space, &mut self.joiner, start, goal, params, &self.batch).map_err(|e| {
            match e {
                BatchedRouteError::Plan(e) => e,
                BatchedRouteError::Join(e) => CgError::Joins { reason: e.reason },
            }
        })
    }
}

/// [`plan`] with every move the foot-level search considers also put to `check` (see
/// [`MoveCheck`]).
pub fn plan_checked(
    space: &mut CgSpace,
    start: (Point2<f64>, f64),
    goal: (Point2<f64>, f64),
    standing: Option<&Standing>,
    params: &PlanParams,
    check: Option<&dyn MoveCheck>,
) -> Result<Plan, CgError> {
    plan_with(
        space,
        start,
        goal,
        standing,
        params,
        check,
        &mut LocalRoutes,
    )
}

/// [`plan_checked`] with its routes (the first and every replanned one) from `routes`.
pub fn plan_with(
    space: &mut CgSpace,
    start: (Point2<f64>, f64),
    goal: (Point2<f64>, f64),
    standing: Option<&Standing>,
    params: &PlanParams,
    check: Option<&dyn MoveCheck>,
    routes_from: &mut dyn RoutePlanner,
) -> Result<Plan, CgError> {
    let grid = *space.grid();
    let cell = |what: &'static str, p: Point2<f64>, theta: f64| {
        grid.cell_of(p, theta).ok_or_else(|| {
            let (lo, hi) = (grid.origin, grid.centre(grid.nx - 1, grid.ny - 1));
            CgError::OutsideMap {
                what,
                x: p.x,
                y: p.y,
                x_min: lo.x,
                x_max: hi.x + grid.cell_m / 2.0,
                y_min: lo.y,
                y_max: hi.y + grid.cell_m / 2.0,
            }
        })
    };
    let s = cell("the start", start.0, start.1)?;
    let g = cell("the goal", goal.0, goal.1)?;
    let g = settle_goal(space, g, goal.0, params.goal_tolerance_m);
    let first_route = routes_from.route(space, s, g, &params.route)?;
    let mut route = first_route.cells.clone();
    let mut marked = Vec::new();
    let mut routes = 1;
    // The steps kept from the last search, and the stance they lead to.
    let mut kept: Vec<FootStep> = Vec::new();
    let mut stance: Option<Stance> = standing.map(|st| {
        Stance::new(
            0,
            st.feet
                .iter()
                .map(|p| p.map(|p| grid.xy_of(p)))
                .collect::<Vec<Option<FootCell>>>(),
            millimetres(st.body_z),
        )
    });
    let mut counts = SearchCounts::default();
    // The cells marked beside the ones the search stuck at, and whether marks are still
    // widened so (see below).
    let mut beside: Vec<CgCell> = Vec::new();
    let mut widen = params.mark_radius > 0;
    let initial = stance.clone();
    let mut first_stance: Option<Stance> = initial.clone();
    // The fewest cell steps to the goal from where a stuck search got, and the stuck
    // searches that got no nearer than that.
    let mut nearest = i32::MAX;
    let mut futile = 0usize;
    // The plan's route, the stance it first chose, its steps and the last search's nodes.
    let (route, first, steps, nodes) = loop {
        let mut search = FootSearch::new(space, &route, params.search.clone());
        if let Some(st) = standing {
            search = search.with_start(start, &st.feet);
        }
        let from = match &stance {
            Some(s) => s.clone(),
            None => search
                .initial_stance()
                .ok_or_else(|| CgError::NoFootfalls {
                    replans: marked.len(),
                    detail: "no stance at the start holds the CG".into(),
                })?,
        };
        // The stance the whole plan starts from: the given one, else the first chosen.
        let first = first_stance.get_or_insert_with(|| from.clone()).clone();
        let searched = search_checked(&mut search, &from, check, &route);
        let this_counts = search.counts();
        counts.add(&this_counts);
        match searched {
            Ok(mut found) => {
                let mut steps = kept.clone();
                steps.append(&mut found.steps);
                break (route, first, steps, found.nodes);
            }
            Err(Failed::Refused(n)) => {
                return Err(CgError::NoFootfalls {
                    replans: marked.len(),
                    detail: format!("the moves' check refused {n} moves of the plans found"),
                });
            }
            Err(Failed::Stuck(fail)) => {
                if let Some((end, mut near)) =
                    arrival_near_goal(space, &route, goal.0, params, &from, &fail, check)
                {
                    tracing::debug!(
                        end,
                        route_len = route.len(),
                        "foot search stuck within the goal's tolerance; the plan ends there"
                    );
                    let mut steps = kept.clone();
                    steps.append(&mut near);
                    route.truncate(end + 1);
                    break (route, first, steps, fail.nodes);
                }
                let left = grid.steps_between(route[fail.furthest], g);
                if left < nearest {
                    nearest = left;
                } else {
                    futile += 1;
                }
                if futile >= params.max_replans
                    || marked.len() >= params.max_replans.saturating_mul(4)
                {
                    return Err(CgError::NoFootfalls {
                        replans: marked.len(),
                        detail: format!(
                            "the search got no further than route cell {} of {}",
                            fail.furthest,
                            route.len()
                        ),
                    });
                }
                let Some(&bad) = route.get(fail.furthest + 1) else {
                    return Err(CgError::NoFootfalls {
                        replans: marked.len(),
                        detail: "the search failed at the goal".into(),
                    });
                };
                // Where the goal's cell cannot be stepped into from the cell before it, that
                // cell is marked instead: the next route comes to the goal from elsewhere.
                let bad = if bad == g && fail.furthest > 0 {
                    route[fail.furthest]
                } else {
                    bad
                };
                if bad == g {
                    return Err(CgError::NoFootfalls {
                        replans: marked.len(),
                        detail: "the goal cell itself cannot be stepped into".into(),
                    });
                }
                tracing::debug!(
                    ?bad,
                    furthest = fail.furthest,
                    from_k = from.k,
                    nodes = fail.nodes,
                    route_len = route.len(),
                    by_legs = this_counts.refused_by_legs,
                    by_check = this_counts.refused_by_check,
                    "foot search stuck; cell marked invalid"
                );
                space.mark_invalid(bad);
                let r = if widen { params.mark_radius.max(0) } else { 0 };
                for dy in -r..=r {
                    for dx in -r..=r {
                        let c = CgCell::new(bad.ix + dx, bad.iy + dy, bad.it);
                        // The cells the route has already passed, the goal and the cells
                        // beside it stay usable (marking those would wall the goal in).
                        let by_goal =
                            c.it == g.it && (c.ix - g.ix).abs() <= 1 && (c.iy - g.iy).abs() <= 1;
                        if c != bad
                            && !by_goal
                            && space.grid().contains(c)
                            && !space.marked().contains(&c)
                            && !route[..=fail.furthest].contains(&c)
                        {
                            space.mark_invalid(c);
                            beside.push(c);
                        }
                    }
                }
                marked.push(bad);
                // Keep the steps up to the stance that reached the route cell `keep` (the
                // furthest, less the back-off, but not before where this search started),
                // and plan the rest of the route from there.
                // The kept steps are put to the outside check first, and end before the
                // first it refuses: the next search starts from a stance the check has seen
                // the robot reach.
                let keep = fail
                    .furthest
                    .saturating_sub(params.backoff_cells)
                    .max(from.k);
                let mut k = from.k;
                let wanted = fail
                    .steps_to_furthest
                    .iter()
                    .take_while(|st| {
                        let go = k < keep;
                        if matches!(st, FootStep::Advance { .. }) {
                            k += 1;
                        }
                        go
                    })
                    .count();
                let (reached, passed) =
                    checked_in_order(&from, &fail.steps_to_furthest[..wanted], &route, check);
                let prefix = fail.steps_to_furthest[..passed].to_vec();
                let keep = reached.k;
                let here = route[keep];
                let rest = routes_from.route(space, here, g, &params.route);
                routes += 1;
                match rest {
                    Ok(r) => {
                        let mut new_route: Vec<CgCell> = route[..keep].to_vec();
                        new_route.extend(r.cells);
                        kept.extend(prefix);
                        stance = Some(reached);
                        route = new_route;
                    }
                    Err(CgError::Unreachable { .. }) | Err(CgError::InvalidEndpoint { .. }) => {
                        // From here there is no way on: replan from the start.
                        let r = match routes_from.route(space, s, g, &params.route) {
                            Ok(r) => r,
                            Err(CgError::Unreachable { .. } | CgError::InvalidEndpoint { .. })
                                if !beside.is_empty() =>
                            {
                                // The cells marked beside those the search stuck at may be
                                // what walls the start or the goal in (a narrow ramp): take
                                // them back, mark only such cells from now on, and try again.
                                tracing::debug!(
                                    taken_back = beside.len(),
                                    "the widened marks walled the way in; keeping the stuck cells only"
                                );
                                for c in beside.drain(..) {
                                    if !marked.contains(&c) {
                                        space.unmark(c);
                                    }
                                }
                                widen = false;
                                routes += 1;
                                routes_from.route(space, s, g, &params.route)?
                            }
                            Err(e) => return Err(e),
                        };
                        routes += 1;
                        route = r.cells;
                        kept.clear();
                        stance = initial.clone();
                        first_stance = initial.clone();
                    }
                    Err(e) => return Err(e),
                }
            }
        }
    };
    let initial_stance = initial.unwrap_or(first);
    Ok(Plan {
        feet: FootPlan {
            route,
            start: Stance {
                k: 0,
                ..initial_stance
            },
            steps,
            nodes,
        },
        first_route,
        marked,
        routes,
        counts,
    })
}

/// Plans the search found that the moves' check refused, at most, before the planner gives
/// up on a route.
const MAX_REFUSED: usize = 400;

/// How a checked search failed.
enum Failed {
    /// The search got stuck.
    Stuck(SearchFailure),
    /// The check refused this many moves of the plans found.
    Refused(usize),
}

/// The cell a plan heads for: the goal's own, or where that is invalid and
/// `tolerance_m` is above 0, the valid cell of the same heading nearest the goal whose centre
/// lies within the tolerance of it (the goal's own cell is kept when there is none, and
/// the route planner then says why it is invalid).
fn settle_goal(space: &mut CgSpace, g: CgCell, goal: Point2<f64>, tolerance_m: f64) -> CgCell {
    if tolerance_m.is_nan() || tolerance_m <= 0.0 || space.is_valid(g) {
        return g;
    }
    let grid = *space.grid();
    let r = (tolerance_m / grid.cell_m).ceil() as i32;
    let mut best: Option<(f64, CgCell)> = None;
    for dy in -r..=r {
        for dx in -r..=r {
            let c = CgCell::new(g.ix + dx, g.iy + dy, g.it);
            if !grid.contains(c) {
                continue;
            }
            let d = (grid.centre(c.ix, c.iy) - goal).norm();
            if d <= tolerance_m && best.is_none_or(|(b, _)| d < b) && space.is_valid(c) {
                best = Some((d, c));
            }
        }
    }
    best.map_or(g, |(_, c)| c)
}

/// Where a stuck search already stood within the goal's tolerance: the last route cell it
/// reached whose centre is within `params.goal_tolerance_m` of `goal`, and the steps from
/// `from` to the first stance on that cell, provided `check` accepts each of them. `None`
/// when the tolerance is 0, no such cell was reached, or a step is refused.
fn arrival_near_goal(
    space: &CgSpace,
    route: &[CgCell],
    goal: Point2<f64>,
    params: &PlanParams,
    from: &Stance,
    fail: &SearchFailure,
    check: Option<&dyn MoveCheck>,
) -> Option<(usize, Vec<FootStep>)> {
    let tolerance = params.goal_tolerance_m;
    // Also refuses a NaN tolerance.
    if tolerance.is_nan() || tolerance <= 0.0 {
        return None;
    }
    let grid = space.grid();
    let near = |k: usize| {
        let c = route[k];
        (grid.centre(c.ix, c.iy) - goal).norm() <= tolerance
    };
    // The furthest route cell within the tolerance and the steps that first reach it.
    let mut best = near(from.k).then_some((from.k, 0));
    let mut at = from.clone();
    for (n, step) in fail.steps_to_furthest.iter().enumerate() {
        apply(&mut at, step);
        if at.k > best.map_or(from.k, |(k, _)| k) && near(at.k) {
            best = Some((at.k, n + 1));
        }
    }
    let (end, n) = best?;
    let steps = &fail.steps_to_furthest[..n];
    let (_, passed) = checked_in_order(from, steps, route, check);
    (passed == n).then(|| (end, steps.to_vec()))
}

/// Puts `steps` from `from` to `check` in order (a stuck search's steps never were: only
/// whole plans are): the stance the accepted ones lead to and how many were accepted, up to
/// the first refused. Without a check every step is accepted.
fn checked_in_order(
    from: &Stance,
    steps: &[FootStep],
    route: &[CgCell],
    check: Option<&dyn MoveCheck>,
) -> (Stance, usize) {
    let mut at = from.clone();
    for (n, step) in steps.iter().enumerate() {
        let mut next = at.clone();
        apply(&mut next, step);
        if let Some(check) = check
            && !check.check(&at, route[at.k], step, &next, route[next.k])
        {
            return (at, n);
        }
        at = next;
    }
    (at, steps.len())
}

/// Searches from `from`, and puts each plan found to `check` move by move; at the first move
/// it refuses, forbids that move from its stance and searches again.
fn search_checked(
    search: &mut FootSearch<'_>,
    from: &Stance,
    check: Option<&dyn MoveCheck>,
    route: &[CgCell],
) -> Result<FootPlan, Failed> {
    let mut refused = 0;
    loop {
        let found = search.search(from.clone()).map_err(Failed::Stuck)?;
        let Some(check) = check else {
            return Ok(found);
        };
        let mut at = from.clone();
        let mut bad = None;
        for step in &found.steps {
            let mut next = at.clone();
            apply(&mut next, step);
            if !check.check(&at, route[at.k], step, &next, route[next.k]) {
                bad = Some(next);
                break;
            }
            at = next;
        }
        match bad {
            None => return Ok(found),
            Some(next) => {
                refused += 1;
                if refused > MAX_REFUSED {
                    return Err(Failed::Refused(refused));
                }
                search.forbid(at, next);
            }
        }
    }
}
