; U-TAMP-1: the original Unified TAMP domain (Agostini and Piater): object-centric
; motion constraints only. No affordance predicates (any member can be grasped in any
; geometrically consistent orientation, anything can be lifted, any up-facing part
; supports anything) and no slide-support. The action parameters are the same as in
; U-TAMP-2, so a U-TAMP-1 plan can be checked against the U-TAMP-2 ground truth.
(define (domain utamp1)
  (:requirements :strips :typing :negative-preconditions)
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
    (isGraspFrom ?obj1 - obj ?o1-mem - obj ?o1m-hp - part ?o1m-hf1 - part ?o1m-hf2 - part))

  (:action pick-support
    :parameters (?obj1 - obj ?o1-mem - obj ?o1-hp - part ?o1-hf1 - part ?o1-hf2 - part
                 ?o1-base - part ?o1-force - part ?obj2 - obj ?o1-o2 - part ?o2-o1 - part)
    :precondition (and
      ; StableGrasp[?obj1, ?o1-mem, hand] without affordances
      (isMember ?obj1 ?o1-mem)
      (oc in workspace ?o1-mem)
      (base ?obj1 ?o1-base)
      (oc ?o1-hp ?obj1 air)
      (oc ?o1-hf1 ?obj1 air)
      (oc ?o1-hf2 ?obj1 air)
      (isAdjacent ?o1-hp ?o1-hf1)
      (isOpposite ?o1-hf1 ?o1-hf2)
      (not (isGraspFrom ?obj1 ?o1-mem ?o1-hp ?o1-hf1 ?o1-hf2))
      (not (isOpposite ?o1-base ?o1-hp))
      (not (isPartEqual ?o1-hp in))
      (oc in hand air)
      (force ?obj1 ?o1-force)
      (oc ?o1-force ?obj1 air)
      (oc ?o1-o2 ?obj1 ?obj2)
      (oc ?o2-o1 ?obj2 ?obj1))
    :effect (and
      (not (oc in hand air)) (oc in hand ?obj1)
      (isGraspFrom ?obj1 ?o1-mem ?o1-hp ?o1-hf1 ?o1-hf2)
      (not (oc ?o1-o2 ?obj1 ?obj2)) (oc ?o1-o2 ?obj1 air)
      (not (oc ?o2-o1 ?obj2 ?obj1)) (oc ?o2-o1 ?obj2 air)))

  (:action place-support
    :parameters (?obj1 - obj ?o1-mem - obj ?o1-hp - part ?o1-hf1 - part ?o1-hf2 - part
                 ?o1-base - part ?o1-force - part ?o1-o2 - part
                 ?obj2 - obj ?o2-base - part ?o2-o1 - part)
    :precondition (and
      (oc in hand ?obj1)
      (isMember ?obj1 ?o1-mem)
      (isGraspFrom ?obj1 ?o1-mem ?o1-hp ?o1-hf1 ?o1-hf2)
      ; StablePlace[?obj1, ?obj2] without affordances
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
      (not (isObjEqual ?obj1 ?obj2)))
    :effect (and
      (not (oc in hand ?obj1)) (oc in hand air)
      (not (isGraspFrom ?obj1 ?o1-mem ?o1-hp ?o1-hf1 ?o1-hf2))
      (not (oc ?o1-o2 ?obj1 air)) (oc ?o1-o2 ?obj1 ?obj2)
      (not (oc ?o2-o1 ?obj2 air)) (oc ?o2-o1 ?obj2 ?obj1)))
)
