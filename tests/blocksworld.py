"""An inline typed blocksworld shared by the parser and validator tests.

It uses negative preconditions, equality and a constant, and mixes the case of names on
purpose (PDDL names are case-insensitive).
"""

DOMAIN = """\
; Typed blocksworld; names are deliberately in mixed case.
(define (domain BW)
  (:requirements :strips :typing :negative-preconditions :equality)
  (:types block slot - surface
          robot)
  (:constants arm - robot)
  (:predicates (on ?b - block ?s - surface) (clear ?s - surface)
               (holding ?r - robot ?b - block) (busy ?r - robot)
               (fitsOn ?b - block ?s - surface))
  (:action pick
    :parameters (?b - block ?s - surface)
    :precondition (and (not (= ?b ?s)) (on ?b ?s) (clear ?b) (not (busy arm)))
    :effect (and (holding arm ?b) (busy arm) (clear ?s) (not (on ?b ?s)) (not (clear ?b))))
  (:action PLACE  ; upper case on purpose
    :parameters (?b - block ?s - surface)
    :precondition (and (holding arm ?b) (clear ?s) (fitsOn ?b ?s) (not (= ?b ?s)))
    :effect (and (on ?b ?s) (clear ?b) (not (clear ?s)) (not (holding arm ?b))
                 (not (busy arm))))
  (:action regrip
    :parameters (?b - block)
    :precondition (holding arm ?b)
    :effect (and (not (holding arm ?b)) (holding arm ?b))))
"""

PROBLEM = """\
(define (problem bw-3)
  (:domain bw)
  (:objects A b c - block s1 s2 s3 - slot)
  (:init (on a s1) (on b s2) (on c s3) (clear a) (clear b) (clear c)
         (fitsOn a b) (fitsOn a c) (fitsOn b c)
         (fitsOn a s1) (fitsOn a s2) (fitsOn a s3) (fitsOn b s1) (fitsOn b s2) (fitsOn b s3)
         (fitsOn c s1) (fitsOn c s2) (fitsOn c s3))
  (:goal (and (on a b) (on b c) (clear s1) (clear s2) (not (busy arm)))))
"""
