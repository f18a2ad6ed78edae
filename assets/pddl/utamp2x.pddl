; U-TAMP-2x: U-TAMP-2 with the grasps a real Panda makes beyond the paper's (extended domain).
; The same types, predicates and actions as utamp2.pddl, and two more actions; its problems
; carry the affordance facts of the extended rules, which the paper's domain never sees: a
; bowl's, a pot's, a tumbler's or a plate's wall pinched at the rim from above
; (utamp_gym.affordances.rim), a handle holding a heavier moment
; (utamp_gym.affordances.hand.EXTENDED_TORQUE_LIMIT), and a flat board slid to the table's
; edge and pinched there (slide-edge and place-edge, utamp_gym.affordances.edge).
; U-TAMP-2: Unified TAMP with inter-object affordances (Niaz, Piater, Agostini).
; Predicates of Table I; StableGrasp / StablePick / StablePlace / StableSlide of Table II.
; Objects are physical objects, their members (body, handle, edges), table slots,
; free spaces and the virtual objects hand, air and workspace. Parts are the six
; sides of a bounding box plus its inside.
(define (domain utamp2x)
  (:requirements :strips :typing :negative-preconditions :conditional-effects)
  (:types obj part)
  (:constants hand air workspace - obj
              on under left right front back in - part)
  (:predicates
    (isObjEqual ?obj1 - obj ?obj2 - obj)
    (isPartEqual ?part1 - part ?part2 - part)
    (oc ?o1-o2 - part ?obj1 - obj ?obj2 - obj)
    (force ?obj - obj ?part - part)
    (base ?obj - obj ?part - part)
    (isMember ?obj1 - obj ?o1-mem - obj)
    (isOpposite ?part1 - part ?part2 - part)
    (isAdjacent ?part1 - part ?part2 - part)
    (isSupportive ?obj - obj ?part - part)
    (isSupportable ?obj - obj ?part - part)
    (isP2PSupportive ?part2 - part ?obj2 - obj ?part1 - part ?obj1 - obj)
    (canGraspFrom ?obj1 - obj ?o1-mem - obj ?o1m-hp - part ?o1m-hf1 - part ?o1m-hf2 - part)
    (isGraspFrom ?obj1 - obj ?o1-mem - obj ?o1m-hp - part ?o1m-hf1 - part ?o1m-hf2 - part)
    (canLift ?obj1 - obj ?o1-mem - obj)
    (canSlide ?obj1 - obj ?obj2 - obj ?o1-o2 - part ?o2-o1 - part)
    (canEdgePinch ?obj1 - obj ?o1-mem - obj ?o1m-hp - part ?o1m-hf1 - part ?o1m-hf2 - part)
    (canSlideEdge ?obj1 - obj ?obj2 - obj ?o1-o2 - part ?o2-o1 - part))

  ; Grasp ?obj1 by its member ?o1-mem (palm on ?o1-hp, fingers on ?o1-hf1/?o1-hf2)
  ; and lift it off its support ?obj2.
  (:action pick-support
    :parameters (?obj1 - obj ?o1-mem - obj ?o1-hp - part ?o1-hf1 - part ?o1-hf2 - part
                 ?o1-base - part ?o1-force - part ?obj2 - obj ?o1-o2 - part ?o2-o1 - part)
    :precondition (and
      ; StableGrasp[?obj1, ?o1-mem, hand]
      (isMember ?obj1 ?o1-mem)
      (oc in workspace ?o1-mem)
      (base ?obj1 ?o1-base)
      (oc ?o1-hp ?obj1 air)
      (oc ?o1-hf1 ?obj1 air)
      (oc ?o1-hf2 ?obj1 air)
      (canGraspFrom ?obj1 ?o1-mem ?o1-hp ?o1-hf1 ?o1-hf2)
      (not (isGraspFrom ?obj1 ?o1-mem ?o1-hp ?o1-hf1 ?o1-hf2))
      (not (isOpposite ?o1-base ?o1-hp))
      (not (isPartEqual ?o1-hp in))
      (oc in hand air)
      ; StablePick[?obj1, ?o1-mem, hand]
      (canLift ?obj1 ?o1-mem)
      ; nothing stands on ?obj1; it rests on ?obj2
      (force ?obj1 ?o1-force)
      (oc ?o1-force ?obj1 air)
      (oc ?o1-o2 ?obj1 ?obj2)
      (oc ?o2-o1 ?obj2 ?obj1))
    :effect (and
      (not (oc in hand air)) (oc in hand ?obj1)
      (isGraspFrom ?obj1 ?o1-mem ?o1-hp ?o1-hf1 ?o1-hf2)
      (not (oc ?o1-o2 ?obj1 ?obj2)) (oc ?o1-o2 ?obj1 air)
      (not (oc ?o2-o1 ?obj2 ?obj1)) (oc ?o2-o1 ?obj2 air)))

  ; Put the held ?obj1 down on part ?o2-o1 of ?obj2, resting on its part ?o1-o2.
  (:action place-support
    :parameters (?obj1 - obj ?o1-mem - obj ?o1-hp - part ?o1-hf1 - part ?o1-hf2 - part
                 ?o1-base - part ?o1-force - part ?o1-o2 - part
                 ?obj2 - obj ?o2-base - part ?o2-o1 - part)
    :precondition (and
      ; StablePick: the hand holds ?obj1 stably from ?o1-mem
      (oc in hand ?obj1)
      (isMember ?obj1 ?o1-mem)
      (isGraspFrom ?obj1 ?o1-mem ?o1-hp ?o1-hf1 ?o1-hf2)
      (canGraspFrom ?obj1 ?o1-mem ?o1-hp ?o1-hf1 ?o1-hf2)
      (canLift ?obj1 ?o1-mem)
      ; StablePlace[?obj1, ?obj2]
      (force ?obj1 ?o1-force)
      (isOpposite ?o1-o2 ?o1-force)
      (oc ?o1-o2 ?obj1 air)
      (isSupportable ?obj1 ?o1-o2)
      (base ?obj1 ?o1-base)
      (isAdjacent ?o1-base ?o1-o2)
      (oc in workspace ?obj2)
      (base ?obj2 ?o2-base)
      (isAdjacent ?o2-base ?o2-o1)
      (oc ?o2-o1 ?obj2 air)
      (force ?obj2 ?o2-o1)
      (isSupportive ?obj2 ?o2-o1)
      (isP2PSupportive ?o2-o1 ?obj2 ?o1-o2 ?obj1)
      (not (isObjEqual ?obj1 ?obj2)))
    :effect (and
      (not (oc in hand ?obj1)) (oc in hand air)
      (not (isGraspFrom ?obj1 ?o1-mem ?o1-hp ?o1-hf1 ?o1-hf2))
      (not (oc ?o1-o2 ?obj1 air)) (oc ?o1-o2 ?obj1 ?obj2)
      (not (oc ?o2-o1 ?obj2 air)) (oc ?o2-o1 ?obj2 ?obj1)))

  ; Grasp an object that cannot be lifted and slide it across its support ?obj2 into
  ; the adjacent free ?space; the hand is free afterwards. The object and all its
  ; members are then in the workspace.
  (:action slide-support
    :parameters (?obj1 - obj ?o1-mem - obj ?o1-hp - part ?o1-hf1 - part ?o1-hf2 - part
                 ?o1-base - part ?obj2 - obj ?o1-o2 - part ?o2-o1 - part
                 ?space - obj ?o1-space - part ?space-o1 - part ?space-o2 - part)
    :precondition (and
      ; StableGrasp[?obj1, ?o1-mem, hand]
      (isMember ?obj1 ?o1-mem)
      (oc in workspace ?o1-mem)
      (base ?obj1 ?o1-base)
      (oc ?o1-hp ?obj1 air)
      (oc ?o1-hf1 ?obj1 air)
      (oc ?o1-hf2 ?obj1 air)
      (canGraspFrom ?obj1 ?o1-mem ?o1-hp ?o1-hf1 ?o1-hf2)
      (not (isGraspFrom ?obj1 ?o1-mem ?o1-hp ?o1-hf1 ?o1-hf2))
      (not (isOpposite ?o1-base ?o1-hp))
      (not (isPartEqual ?o1-hp in))
      (oc in hand air)
      ; ?obj1 rests on ?obj2
      (oc ?o1-o2 ?obj1 ?obj2)
      (oc ?o2-o1 ?obj2 ?obj1)
      ; StableSlide[?obj1, ?o1-mem, ?obj2, ?space]
      (not (canLift ?obj1 ?o1-mem))
      (canSlide ?obj1 ?obj2 ?o1-o2 ?o2-o1)
      (isAdjacent ?o1-space ?o1-o2)
      (not (isAdjacent ?o1-space ?o1-hf1))
      (not (isAdjacent ?o1-space ?o1-hf2))
      (oc ?o1-space ?obj1 ?space)
      (oc ?o2-o1 ?obj2 ?space)
      (oc in workspace ?space)
      (oc in ?space air)
      (oc ?space-o2 ?space ?obj2)
      (oc ?space-o1 ?space ?obj1)
      (isAdjacent ?space-o1 ?space-o2))
    :effect (and
      (not (oc in ?space air)) (oc in ?space ?obj1)
      (not (oc ?o1-space ?obj1 ?space)) (not (oc ?space-o1 ?space ?obj1))
      (oc in workspace ?obj1)
      ; sliding brings every member of ?obj1 into the workspace with it
      (forall (?m - obj) (when (isMember ?obj1 ?m) (oc in workspace ?m)))))

  ; Press the flat ?obj1 from above and drag it across its fixed support ?obj2 until it
  ; overhangs the table's edge, pinch the overhang (palm on ?o1-hp, the fingers closing on
  ; ?o1-hf1/?o1-hf2, its top and bottom) and lift it: the hand then holds it.
  (:action slide-edge
    :parameters (?obj1 - obj ?o1-mem - obj ?o1-hp - part ?o1-hf1 - part ?o1-hf2 - part
                 ?o1-base - part ?o1-force - part ?obj2 - obj ?o1-o2 - part ?o2-o1 - part)
    :precondition (and
      (isMember ?obj1 ?o1-mem)
      (oc in workspace ?o1-mem)
      (base ?obj1 ?o1-base)
      (canEdgePinch ?obj1 ?o1-mem ?o1-hp ?o1-hf1 ?o1-hf2)
      (oc in hand air)
      ; nothing stands on ?obj1; it rests on ?obj2, across which it can be dragged
      (force ?obj1 ?o1-force)
      (oc ?o1-force ?obj1 air)
      (oc ?o1-o2 ?obj1 ?obj2)
      (oc ?o2-o1 ?obj2 ?obj1)
      (canSlideEdge ?obj1 ?obj2 ?o1-o2 ?o2-o1))
    :effect (and
      (not (oc in hand air)) (oc in hand ?obj1)
      (isGraspFrom ?obj1 ?o1-mem ?o1-hp ?o1-hf1 ?o1-hf2)
      (not (oc ?o1-o2 ?obj1 ?obj2)) (oc ?o1-o2 ?obj1 air)
      (not (oc ?o2-o1 ?obj2 ?obj1)) (oc ?o2-o1 ?obj2 air)))

  ; Put the edge-pinched ?obj1 down on the table's edge and drag it onto the fixed ?obj2
  ; (a table slot), resting on its part ?o1-o2.
  (:action place-edge
    :parameters (?obj1 - obj ?o1-mem - obj ?o1-hp - part ?o1-hf1 - part ?o1-hf2 - part
                 ?o1-base - part ?o1-force - part ?o1-o2 - part
                 ?obj2 - obj ?o2-base - part ?o2-o1 - part)
    :precondition (and
      (oc in hand ?obj1)
      (isMember ?obj1 ?o1-mem)
      (isGraspFrom ?obj1 ?o1-mem ?o1-hp ?o1-hf1 ?o1-hf2)
      (canEdgePinch ?obj1 ?o1-mem ?o1-hp ?o1-hf1 ?o1-hf2)
      (force ?obj1 ?o1-force)
      (isOpposite ?o1-o2 ?o1-force)
      (oc ?o1-o2 ?obj1 air)
      (base ?obj1 ?o1-base)
      (isAdjacent ?o1-base ?o1-o2)
      (oc in workspace ?obj2)
      (base ?obj2 ?o2-base)
      (isAdjacent ?o2-base ?o2-o1)
      (oc ?o2-o1 ?obj2 air)
      (force ?obj2 ?o2-o1)
      (canSlideEdge ?obj1 ?obj2 ?o1-o2 ?o2-o1)
      (isP2PSupportive ?o2-o1 ?obj2 ?o1-o2 ?obj1)
      (not (isObjEqual ?obj1 ?obj2)))
    :effect (and
      (not (oc in hand ?obj1)) (oc in hand air)
      (not (isGraspFrom ?obj1 ?o1-mem ?o1-hp ?o1-hf1 ?o1-hf2))
      (not (oc ?o1-o2 ?obj1 air)) (oc ?o1-o2 ?obj1 ?obj2)
      (not (oc ?o2-o1 ?obj2 air)) (oc ?o2-o1 ?obj2 ?obj1)))
)
